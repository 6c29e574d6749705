// Marching tetrahedra on a CUDA Device (tetiso/device.hpp): the domain put
// on the device, then the passes of marching_tets.hpp over the CUDA backend
// (exec_cuda.cuh), the host's passes with the host's per-element functions.
// A domain's arrays are uploaded; a lattice domain is built on the device
// instead, its nodes from lattice_cells.hpp, a built-in field's values from
// field_formulas.hpp (an expression's computed on the host and uploaded),
// its tetrahedra computed from their index by each pass that reads one.
//
// Bit-identical to the host: the per-element functions are compiled with
// --fmad=false (no fused multiply-add, as the host is built with
// -ffp-contract=off) and IEEE division (nvcc's default -prec-div=true).
#include <cuda_runtime.h>

#include <chrono>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "device_cuda.cuh"
#include "extract_rules.hpp"
#include "field_formulas.hpp"
#include "lattice_cells.hpp"
#include "marching_tets.hpp"
#include "tetiso/error.hpp"
#include "tetiso/lattice.hpp"

namespace tetiso {
namespace {

using i64 = std::int64_t;
using u8 = std::uint8_t;

template <class T, class Allocator>
void upload(cuda::DeviceArray<T>& device, const std::vector<T, Allocator>& host, cudaStream_t stream,
            const char* what) {
    device.resize(host.size());
    if (!host.empty())
        cuda::check(cudaMemcpyAsync(device.data(), host.data(), host.size() * sizeof(T), cudaMemcpyHostToDevice, stream),
                    what);
}

template <class Tets>
DeviceSurface march_here(CudaExec& exec, ExtractionBuffers& b, std::size_t nodes, const Tets& tets,
                         std::size_t tet_count, float level, int domain) {
    const extract_rules::NodeView view{b.x.data(),   b.y.data(),         b.z.data(),      b.f.data(),
                                       b.gid.data(), b.interface.data(), b.shared.data(), b.shared.size()};
    const marching::Surface s = marching::march(exec, b.passes, view, static_cast<i64>(nodes), tets,
                                                static_cast<i64>(tet_count), level, domain);
    exec.sync();
    return DeviceSurface{s.x, s.y, s.z, s.key, s.flags, s.triangles, s.vertices, s.triangle_count, domain};
}

} // namespace

DeviceSurface Device::State::extract(const Domain& domain, float level) {
    extract_rules::check_domain(domain);
    extract_rules::check_level(level);
    use_device();
    ExtractionBuffers& b = extraction;
    auto start = std::chrono::steady_clock::now();
    upload(b.x, domain.x, stream, "uploading x");
    upload(b.y, domain.y, stream, "uploading y");
    upload(b.z, domain.z, stream, "uploading z");
    upload(b.f, domain.f, stream, "uploading f");
    upload(b.gid, domain.gid, stream, "uploading node ids");
    upload(b.interface, domain.interface, stream, "uploading interface masks");
    upload(b.shared, domain.shared_edges, stream, "uploading shared edges");
    upload(b.tets, domain.tets, stream, "uploading tetrahedra");
    cuda::check(cudaStreamSynchronize(stream), "uploading the domain");
    timings.upload = seconds_since(start);
    start = std::chrono::steady_clock::now();
    const DeviceSurface surface = march_here(*exec, b, domain.node_count(), marching::TetArray{b.tets.data()},
                                             domain.tet_count(), level, domain.id);
    timings.extract = seconds_since(start);
    return surface;
}

DeviceSurface Device::State::extract(const Decomposition& decomposition, int domain, const Field& field, float level) {
    const CellBox& box = decomposition.box(domain);
    const std::size_t nodes = decomposition.node_count(domain);
    if (nodes > static_cast<std::size_t>(INT32_MAX) / extract_rules::kBucket)
        throw Error(extract_rules::domain_name(domain) + ": too many nodes for one domain (" + std::to_string(nodes) +
                    ")");
    extract_rules::check_level(level);
    use_device();
    ExtractionBuffers& b = extraction;
    auto start = std::chrono::steady_clock::now();
    // A built-in field is evaluated on the device; another (an expression)
    // on the host, its values uploaded.
    const std::optional<BuiltinField> builtin = field.builtin();
    if (!builtin) upload(b.f, decomposition.field_values(domain, field), stream, "uploading f");
    else b.f.resize(nodes);
    cuda::check(cudaStreamSynchronize(stream), "uploading the field values");
    timings.upload = seconds_since(start);

    start = std::chrono::steady_clock::now();
    const lattice_cells::Box cells = lattice_cells::box_of(decomposition.lattice(), box, decomposition.open_faces(domain));
    b.x.resize(nodes);
    b.y.resize(nodes);
    b.z.resize(nodes);
    b.gid.resize(nodes);
    b.interface.resize(nodes);
    b.shared.resize(0); // a box's node masks tell its shared edges
    float *x = b.x.data(), *y = b.y.data(), *z = b.z.data(), *f = b.f.data();
    GlobalId* gid = b.gid.data();
    u8* interface = b.interface.data();
    const bool evaluate = builtin.has_value();
    const BuiltinField kind = builtin.value_or(BuiltinField::paper);
    exec->for_each(static_cast<i64>(nodes), [=] __device__(i64 v) {
        const lattice_cells::Node node = lattice_cells::node(cells, v);
        x[v] = static_cast<float>(node.x);
        y[v] = static_cast<float>(node.y);
        z[v] = static_cast<float>(node.z);
        gid[v] = node.gid;
        interface[v] = node.interface;
        if (evaluate) f[v] = static_cast<float>(field_formulas::value(kind, node.x, node.y, node.z));
    });
    const DeviceSurface surface = march_here(*exec, b, nodes, marching::LatticeTets{cells},
                                             static_cast<std::size_t>(box.cells()) * 6, level, domain);
    timings.extract = seconds_since(start);
    return surface;
}

Piece Device::State::download(const DeviceSurface& s) {
    const auto start = std::chrono::steady_clock::now();
    Piece piece;
    auto fetch = [&](auto& host, const auto* device, std::size_t n) {
        host.resize(n);
        if (n)
            cuda::check(cudaMemcpyAsync(host.data(), device, n * sizeof(host[0]), cudaMemcpyDeviceToHost, stream),
                        "downloading the piece");
    };
    const auto nv = static_cast<std::size_t>(s.vertices), nt = static_cast<std::size_t>(s.triangle_count);
    fetch(piece.x, s.x, nv);
    fetch(piece.y, s.y, nv);
    fetch(piece.z, s.z, nv);
    fetch(piece.key, s.key, nv);
    fetch(piece.flags, s.flags, nv);
    fetch(piece.triangles, s.triangles, 3 * nt);
    cuda::check(cudaStreamSynchronize(stream), "downloading the piece");
    piece.domains = {s.domain};
    timings.download = seconds_since(start);
    return piece;
}

} // namespace tetiso
