// Reduction of a piece (reduce.hpp): the input and option checks, then the
// round driver (rounds.hpp) over the OpenMP backend, or the CUDA Device's
// (reduce_gpu.cu) where the options name one.
#include "tetiso/reduce.hpp"
#include "tetiso/detail/reduce_policy.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "../device_entry.hpp"
#include "../exec_host.hpp"
#include "batch.hpp"
#include "input.hpp"
#include "rounds.hpp"
#include "tetiso/detail/reduce_policy.hpp"
#include "tetiso/error.hpp"

namespace tetiso {

using reduction::i32;

void check_reduce_input(const Piece& in) {
    const std::size_t nv = in.key.size();
    if (in.x.size() != nv || in.y.size() != nv || in.z.size() != nv)
        throw Error("tetiso::reduce: x, y, z and key differ in length");
    if (!in.flags.empty() && in.flags.size() != nv) throw Error("tetiso::reduce: flags and key differ in length");
    if (in.triangles.size() % 3 != 0) throw Error("tetiso::reduce: the triangle array is not a multiple of 3");
    if (!in.error.empty() && in.error.size() != in.triangle_count())
        throw Error("tetiso::reduce: error and triangles differ in length");
    for (std::size_t t = 0; t < in.error.size(); ++t)
        if (!(in.error[t] >= 0.0f && std::isfinite(in.error[t])))
            throw Error("tetiso::reduce: triangle " + std::to_string(t) + " has an error bound that is not a finite non-negative number");
    if (in.sample_xyz.size() != 3 * in.sample_triangle.size())
        throw Error("tetiso::reduce: sample_xyz is not three coordinates per sample_triangle");
    if ((!in.sample_triangle.empty() || !in.sampled.empty()) && in.error.empty())
        throw Error("tetiso::reduce: samples without error bounds (a raw surface's samples are its vertices)");
    if (!in.sampled.empty() && in.sampled.size() != in.triangle_count())
        throw Error("tetiso::reduce: sampled and triangles differ in length");
    for (std::size_t i = 0; i < in.sample_count(); ++i) {
        const i32 t = in.sample_triangle[i];
        if (t < 0 || static_cast<std::size_t>(t) >= in.triangle_count())
            throw Error("tetiso::reduce: sample " + std::to_string(i) + " refers to triangle " + std::to_string(t) +
                        " of " + std::to_string(in.triangle_count()));
        if (!in.triangle_sampled(static_cast<std::size_t>(t)))
            throw Error("tetiso::reduce: sample " + std::to_string(i) + " is held by triangle " + std::to_string(t) +
                        ", which is not marked sampled");
        for (std::size_t c = 0; c < 3; ++c)
            if (!std::isfinite(in.sample_xyz[3 * i + c]))
                throw Error("tetiso::reduce: sample " + std::to_string(i) + " has a coordinate that is not finite");
    }
    if (nv > static_cast<std::size_t>(std::numeric_limits<i32>::max() / 2) ||
        in.triangles.size() > static_cast<std::size_t>(std::numeric_limits<i32>::max() / 2))
        throw Error("tetiso::reduce: mesh too large for 32-bit indices");
    for (std::size_t v = 1; v < nv; ++v)
        if (!(in.key[v - 1] < in.key[v]))
            throw Error("tetiso::reduce: vertex keys are not sorted and unique at vertex " + std::to_string(v) +
                        " (key " + std::to_string(in.key[v]) + ")");
    for (std::size_t v = 0; v < nv; ++v)
        if (!std::isfinite(in.x[v]) || !std::isfinite(in.y[v]) || !std::isfinite(in.z[v]))
            throw Error("tetiso::reduce: vertex (key " + std::to_string(in.key[v]) +
                        ") has a coordinate that is not finite");
    for (std::size_t t = 0; t < in.triangle_count(); ++t) {
        const i32 a = in.triangles[3 * t], b = in.triangles[3 * t + 1], c = in.triangles[3 * t + 2];
        for (const i32 v : {a, b, c})
            if (v < 0 || static_cast<std::size_t>(v) >= nv)
                throw Error("tetiso::reduce: triangle " + std::to_string(t) + " refers to vertex " +
                            std::to_string(v) + " of " + std::to_string(nv));
        if (a == b || b == c || c == a)
            throw Error("tetiso::reduce: triangle " + std::to_string(t) + " repeats vertex (key " +
                        std::to_string(in.key[static_cast<std::size_t>(a == b || a == c ? a : b)]) + ")");
    }
}

void check_reduce_options(const ReduceOptions& o) {
    auto bad = [](const std::string& what) { throw Error("tetiso::reduce: " + what); };
    if (!(o.phi > 0.0 && o.phi <= 1.0)) bad("phi = " + std::to_string(o.phi) + " is outside (0, 1]");
    if (o.threads < 0) bad("threads = " + std::to_string(o.threads) + " is negative");
    if (o.max_rounds < 0) bad("max_rounds = " + std::to_string(o.max_rounds) + " is negative");
    if (!(o.min_angle_degrees >= 0.0 && o.min_angle_degrees <= 30.0))
        bad("min_angle_degrees = " + std::to_string(o.min_angle_degrees) + " is outside [0, 30]");
    if (std::isnan(o.max_error)) bad("max_error is NaN");
    if (o.obstacles.size() % 9 != 0) bad("obstacles is not nine coordinates per triangle");
    for (const float c : o.obstacles)
        if (!std::isfinite(c)) bad("obstacles has a coordinate that is not finite");
    if (!(o.max_normal_turn_degrees > 0.0 && o.max_normal_turn_degrees < 90.0))
        bad("max_normal_turn_degrees = " + std::to_string(o.max_normal_turn_degrees) + " is outside (0, 90)");
    if (!(o.short_edge_ratio >= 0.0 && o.short_edge_ratio < 1.0))
        bad("short_edge_ratio = " + std::to_string(o.short_edge_ratio) + " is outside [0, 1)");
    if (!(o.flip_max_dihedral_degrees >= 0.0 && o.flip_max_dihedral_degrees < 90.0))
        bad("flip_max_dihedral_degrees = " + std::to_string(o.flip_max_dihedral_degrees) + " is outside [0, 90)");
}

namespace {

Piece reduce_on_host(const Piece& in, const ReduceOptions& options, ReduceReport* report, bool reservations,
                     long window, detail::Speculation speculation) {
    const auto start = std::chrono::steady_clock::now();
    check_reduce_options(options);
    check_reduce_input(in);
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    rep = ReduceReport{};
    rep.triangles_in = in.triangle_count();
    rep.vertices_in = in.vertex_count();

    HostExec exec;
    const int available = parallel::resolve_threads(options.threads);
    exec.threads = std::min(available, reduction::kMaxRoundThreads);
    reduction::ReductionState<HostExec> state;
    state.selection.always_reservations = reservations;
    state.selection.window_override = window;
    state.selection.speculate = speculation != detail::Speculation::kNone;
    if (speculation == detail::Speculation::kSamplesWhenDecided) state.selection.optimistic_min = 0;
    reduction::load_piece(exec, in, options.max_error > 0, state);
    reduction::run_rounds(exec, state, options, available, rep);
    Piece out = reduction::unload_piece(exec, state, options.keep_samples);
    out.domains = in.domains;
    rep.triangles_out = out.triangle_count();
    rep.vertices_out = out.vertex_count();
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return out;
}

} // namespace

Piece reduce(const Piece& in, const ReduceOptions& options, ReduceReport* report, StageSeconds* seconds) {
    if (options.device.is_gpu()) return on_gpu::reduce(options.device.state(), in, options, report, seconds);
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    Piece out = reduce_on_host(in, options, &rep, false, 0, detail::Speculation::kNone);
    if (seconds) seconds->reduce += rep.seconds;
    return out;
}

void check_batch_input(const std::vector<Piece>& pieces) {
    for (std::size_t i = 0; i < pieces.size(); ++i) {
        try {
            check_reduce_input(pieces[i]);
        } catch (const Error& e) {
            throw batch_error(i, e);
        }
    }
}

Error batch_error(std::size_t piece, const Error& e) {
    std::string what = e.what();
    const std::string alone = "tetiso::reduce: ";
    if (what.starts_with(alone)) what.erase(0, alone.size());
    return Error("tetiso::reduce_batch: piece " + std::to_string(piece) + ": " + what);
}

std::vector<Piece> reduce_batch(const std::vector<Piece>& pieces, const ReduceOptions& options, ReduceReport* report,
                                StageSeconds* seconds) {
    if (options.device.is_gpu()) return on_gpu::reduce_batch(options.device.state(), pieces, options, report, seconds);
    const auto start = std::chrono::steady_clock::now();
    check_reduce_options(options);
    check_batch_input(pieces);
    if (pieces.empty()) return {};
    ReduceReport local_report;
    ReduceReport& rep = report ? *report : local_report;
    rep = ReduceReport{};
    for (const Piece& p : pieces) {
        rep.triangles_in += p.triangle_count();
        rep.vertices_in += p.vertex_count();
    }
    HostExec exec;
    const int available = parallel::resolve_threads(options.threads);
    exec.threads = std::min(available, reduction::kMaxRoundThreads);
    reduction::ReductionState<HostExec> state;
    reduction::load_pieces(exec, pieces, options.max_error > 0, state);
    try {
        reduction::run_rounds(exec, state, options, available, rep);
    } catch (const Error& e) {
        if (state.fans.faulty < 0) throw;
        throw batch_error(static_cast<std::size_t>(exec.get(state.vertex_piece, state.fans.faulty)), e);
    }
    std::vector<Piece> out = reduction::unload_pieces(exec, state, options.keep_samples);
    for (std::size_t i = 0; i < out.size(); ++i) {
        out[i].domains = pieces[i].domains;
        rep.triangles_out += out[i].triangle_count();
        rep.vertices_out += out[i].vertex_count();
    }
    rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (seconds) seconds->reduce += rep.seconds;
    return out;
}

namespace detail {
Piece reduce_by_reservations(const Piece& in, const ReduceOptions& options, long window, Speculation speculation,
                             ReduceReport* report) {
    return reduce_on_host(in, options, report, true, window, speculation);
}
} // namespace detail

} // namespace tetiso
