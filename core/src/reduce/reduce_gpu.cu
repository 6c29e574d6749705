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
#include "batch.hpp"
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
    st.pieces = 1;
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

std::vector<Piece> Device::State::reduce_batch(const std::vector<Piece>& pieces, const ReduceOptions& options,
                                               ReduceReport* report) {
    const auto start = std::chrono::steady_clock::now();
    check_reduce_options(options);
    check_batch_input(pieces);
    if (pieces.empty()) return {};
    use_device();
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    start_report(rep, 0, 0);
    for (const Piece& p : pieces) {
        rep.triangles_in += p.triangle_count();
        rep.vertices_in += p.vertex_count();
    }
    auto t = std::chrono::steady_clock::now();
    reduction::load_pieces(*exec, pieces, options.max_error > 0, reduction);
    exec->sync();
    timings.upload += seconds_since(t);
    t = std::chrono::steady_clock::now();
    try {
        reduction::run_rounds(*exec, reduction, options, 1, rep);
    } catch (const Error& e) {
        if (reduction.fans.faulty < 0) throw;
        throw batch_error(static_cast<std::size_t>(exec->get(reduction.vertex_piece, reduction.fans.faulty)), e);
    }
    timings.reduce += seconds_since(t);
    t = std::chrono::steady_clock::now();
    std::vector<Piece> out = reduction::unload_pieces(*exec, reduction, options.keep_samples);
    timings.download += seconds_since(t);
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i].domains = pieces[i].domains;
        rep.triangles_out += out[i].triangle_count();
        rep.vertices_out += out[i].vertex_count();
    }
    rep.seconds = seconds_since(start);
    return out;
}

void Device::State::begin_batch() {
    batch_domains.clear();
    reduction.s.nv = reduction.s.nt = 0;
    reduction.vertex_piece.resize(0);
}

// The surface's arrays copied after those of the batch, its triangles'
// corners shifted by the vertices before it.
void Device::State::append_to_batch(const DeviceSurface& d) {
    if (breaks_input_rules(*exec, d)) check_reduce_input(download(d));
    reduction::Surface<CudaExec>& s = reduction.s;
    const i32 base_v = s.nv, base_t = s.nt;
    const auto nv = static_cast<std::size_t>(base_v) + static_cast<std::size_t>(d.vertices);
    const auto nt = static_cast<std::size_t>(base_t) + static_cast<std::size_t>(d.triangle_count);
    s.xyz.resize(3 * nv);
    s.key.resize(nv);
    s.flags.resize(nv);
    s.tri.resize(3 * nt);
    s.err.resize(nt);
    reduction.vertex_piece.resize(nv);
    float* xyz = s.xyz.data() + 3 * static_cast<std::size_t>(base_v);
    i32* piece = reduction.vertex_piece.data() + base_v;
    const i32 index = static_cast<i32>(batch_domains.size());
    const float *x = d.x, *y = d.y, *z = d.z;
    exec->for_each(d.vertices, [=] __device__(i64 v) {
        xyz[3 * v] = x[v];
        xyz[3 * v + 1] = y[v];
        xyz[3 * v + 2] = z[v];
        piece[v] = index;
    });
    i32* tri = s.tri.data() + 3 * static_cast<std::size_t>(base_t);
    float* err = s.err.data() + base_t;
    const i32* from = d.triangles;
    exec->for_each(3 * static_cast<i64>(d.triangle_count), [=] __device__(i64 c) {
        tri[c] = from[c] + base_v;
        if (c % 3 == 0) err[c / 3] = 0.0f;
    });
    if (d.vertices) {
        cuda::check(cudaMemcpyAsync(s.key.data() + base_v, d.key, d.vertices * sizeof(EdgeKey), cudaMemcpyDeviceToDevice,
                                    stream),
                    "keys");
        cuda::check(cudaMemcpyAsync(s.flags.data() + base_v, d.flags, static_cast<std::size_t>(d.vertices),
                                    cudaMemcpyDeviceToDevice, stream),
                    "flags");
    }
    s.nv = static_cast<i32>(nv);
    s.nt = static_cast<i32>(nt);
    batch_domains.push_back(d.domain);
}

std::vector<Piece> Device::State::reduce_batch(const ReduceOptions& options, ReduceReport* report) {
    const auto start = std::chrono::steady_clock::now();
    check_reduce_options(options);
    if (batch_domains.empty()) return {};
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    start_report(rep, static_cast<std::size_t>(reduction.s.nt), static_cast<std::size_t>(reduction.s.nv));
    const auto t = std::chrono::steady_clock::now();
    reduction.pieces = static_cast<i32>(batch_domains.size());
    reduction.fans.faulty = -1;
    reduction.samples.on = false;
    if (options.max_error > 0)
        reduction::build_raw_samples(*exec, reduction.s.view(), reduction.samples, reduction.scratch, reduction.rank);
    reduction::run_rounds(*exec, reduction, options, 1, rep);
    timings.reduce += seconds_since(t);
    const auto t_down = std::chrono::steady_clock::now();
    std::vector<Piece> out = reduction::unload_pieces(*exec, reduction, options.keep_samples);
    timings.download += seconds_since(t_down);
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i].domains = {batch_domains[i]};
        rep.triangles_out += out[i].triangle_count();
        rep.vertices_out += out[i].vertex_count();
    }
    rep.seconds = seconds_since(start);
    return out;
}

} // namespace tetiso
