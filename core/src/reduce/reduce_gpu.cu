// Reduction on a CUDA Device (tetiso/device.hpp): the round driver (rounds.hpp)
// over the CUDA backend (exec_cuda.cuh), so the per-element functions and
// the order of every step are the host's and the piece is reduce()'s, byte
// for byte. A host piece is uploaded and checked as reduce() checks it; a
// domain's surface extracted on the device (a domain's task) never
// leaves it: it is checked there, and handed to the reduction in place.
#include <cuda_runtime.h>

#include <chrono>
#include <cstdint>

#include "../device_cuda.cuh"
#include "input.hpp"
#include "rounds.hpp"
#include "tetiso/error.hpp"

namespace tetiso {
namespace {

using reduction::i32;
using reduction::i64;
using reduction::u8;

// Whether a surface extracted on the device breaks a rule reduce() checks
// (coordinates finite, keys ascending and unique, triangles naming three
// distinct vertices): the extraction keeps them by construction, save for a
// domain whose nodes have coordinates that are not finite.
bool breaks_input_rules(CudaExec& exec, const DeviceSurface& d) {
    const float *x = d.x, *y = d.y, *z = d.z;
    const EdgeKey* key = d.key;
    const i32 nv = d.vertices;
    if (exec.count(nv, [=] __device__(i64 v) {
            return !isfinite(x[v]) || !isfinite(y[v]) || !isfinite(z[v]) || (v + 1 < nv && !(key[v] < key[v + 1]));
        }) > 0)
        return true;
    const i32* tri = d.triangles;
    return exec.count(d.triangle_count, [=] __device__(i64 t) {
        const i32 a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
        return a < 0 || b < 0 || c < 0 || a >= nv || b >= nv || c >= nv || a == b || b == c || c == a;
    }) > 0;
}

// The reduction's surface from an extracted one, as load_piece() makes it
// from a piece.
void load_device_surface(CudaExec& exec, const DeviceSurface& d, bool bounded,
                         reduction::ReductionState<CudaExec>& st) {
    reduction::Surface<CudaExec>& s = st.s;
    const auto nv = static_cast<std::size_t>(d.vertices), nt = static_cast<std::size_t>(d.triangle_count);
    s.xyz.resize(3 * nv);
    s.key.resize(nv);
    s.flags.resize(nv);
    s.tri.resize(3 * nt);
    exec.assign(s.err, static_cast<i64>(nt), 0.0f);
    float* xyz = s.xyz.data();
    const float *x = d.x, *y = d.y, *z = d.z;
    exec.for_each(static_cast<i64>(nv), [=] __device__(i64 v) {
        xyz[3 * v] = x[v];
        xyz[3 * v + 1] = y[v];
        xyz[3 * v + 2] = z[v];
    });
    const cudaStream_t stream = exec.stream();
    if (nv) {
        cuda::check(cudaMemcpyAsync(s.key.data(), d.key, nv * sizeof(EdgeKey), cudaMemcpyDeviceToDevice, stream), "keys");
        cuda::check(cudaMemcpyAsync(s.flags.data(), d.flags, nv, cudaMemcpyDeviceToDevice, stream), "flags");
    }
    if (nt)
        cuda::check(cudaMemcpyAsync(s.tri.data(), d.triangles, 3 * nt * sizeof(i32), cudaMemcpyDeviceToDevice, stream),
                    "triangles");
    s.nv = d.vertices;
    s.nt = d.triangle_count;
    st.samples.on = false;
    if (bounded) reduction::build_raw_samples(exec, s.view(), st.samples, st.scratch, st.rank);
}

void start_report(ReduceReport& rep, std::size_t triangles, std::size_t vertices) {
    rep = ReduceReport{};
    rep.triangles_in = triangles;
    rep.vertices_in = vertices;
}

void finish_report(ReduceReport& rep, const Piece& out, std::chrono::steady_clock::time_point start) {
    rep.triangles_out = out.triangle_count();
    rep.vertices_out = out.vertex_count();
    rep.seconds = seconds_since(start);
}

} // namespace

Piece Device::State::reduce(const Piece& in, const ReduceOptions& options, ReduceReport* report) {
    const auto start = std::chrono::steady_clock::now();
    check_reduce_options(options);
    check_reduce_input(in);
    use_device();
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    start_report(rep, in.triangle_count(), in.vertex_count());
    auto t = std::chrono::steady_clock::now();
    reduction::load_piece(*exec, in, options.max_error > 0, reduction);
    exec->sync();
    timings.upload += seconds_since(t);
    t = std::chrono::steady_clock::now();
    reduction::run_rounds(*exec, reduction, options, 1, rep);
    timings.reduce += seconds_since(t);
    t = std::chrono::steady_clock::now();
    Piece out = reduction::unload_piece(*exec, reduction, options.keep_samples);
    out.domains = in.domains;
    timings.download += seconds_since(t);
    finish_report(rep, out, start);
    return out;
}

// The report's seconds are the reduction's, from the surface on the device
// to the piece on the host (the extraction's are in timings).
Piece Device::State::reduce(const DeviceSurface& surface, const ReduceOptions& options, ReduceReport* report) {
    const auto start = std::chrono::steady_clock::now();
    check_reduce_options(options);
    // A surface that breaks reduce()'s rules comes back, to be refused with
    // the message the CPU gives.
    if (breaks_input_rules(*exec, surface)) check_reduce_input(download(surface));
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    start_report(rep, static_cast<std::size_t>(surface.triangle_count), static_cast<std::size_t>(surface.vertices));
    const auto t = std::chrono::steady_clock::now();
    load_device_surface(*exec, surface, options.max_error > 0, reduction);
    reduction::run_rounds(*exec, reduction, options, 1, rep);
    timings.reduce += seconds_since(t);
    const auto t_down = std::chrono::steady_clock::now();
    Piece out = reduction::unload_piece(*exec, reduction, options.keep_samples);
    out.domains = {surface.domain};
    timings.download += seconds_since(t_down);
    finish_report(rep, out, start);
    return out;
}

} // namespace tetiso
