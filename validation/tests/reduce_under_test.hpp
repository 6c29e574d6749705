// The reduction a suite tests. Every call also reduces the piece in a batch
// (reduce_batch) beside other pieces, each of which must come out as it
// does alone, byte for byte, or with reduce()'s error naming the piece. In
// the suite's GPU build (TETISO_TEST_GPU, label gpu) every call runs on the
// GPU too, alone and batched, whose piece, or error message, must be the
// CPU's byte for byte, and whose rounds choose the same number of
// collapses and flips; where there is no GPU that build skips. So every
// case of the CPU suite is a case of the GPU's, with its own assertions.
#pragma once

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/reduce.hpp"

#ifdef TETISO_TEST_GPU
#include "tetiso/device.hpp"
#endif

namespace tetiso::test {

// Names the first array that differs.
inline ::testing::AssertionResult same_piece(const Piece& expected, const Piece& got) {
    const auto differ = [](const char* what) { return ::testing::AssertionFailure() << what << " differ"; };
    if (expected.key != got.key) return differ("keys");
    if (!same_bits(expected.x, got.x) || !same_bits(expected.y, got.y) || !same_bits(expected.z, got.z))
        return differ("positions");
    if (expected.flags != got.flags) return differ("flags");
    if (expected.triangles != got.triangles) return differ("triangles");
    if (!same_bits(expected.error, got.error)) return differ("error bounds");
    if (!same_bits(expected.sample_xyz, got.sample_xyz) || expected.sample_triangle != got.sample_triangle ||
        expected.sampled != got.sampled)
        return differ("samples");
    if (expected.domains != got.domains) return differ("domain lists");
    return ::testing::AssertionSuccess();
}

// A piece of one triangle: no operation is possible, so alone it finishes
// in round 0.
inline Piece one_triangle() {
    Piece p;
    p.x = {0.0f, 1.0f, 0.0f};
    p.y = {0.0f, 0.0f, 1.0f};
    p.z = {0.0f, 0.0f, 0.0f};
    p.key = {7, 8, 9};
    p.flags = {0, 0, 0};
    p.triangles = {0, 1, 2};
    return p;
}

// What reduce_batch must throw for a batch whose piece `index` alone throws
// `alone` (bad options are the batch's, named as reduce() names them).
inline std::string batch_error_for(const std::string& alone, std::size_t index, bool options_error) {
    if (options_error) return alone;
    const std::string prefix = "tetiso::reduce: ";
    const std::string what = alone.rfind(prefix, 0) == 0 ? alone.substr(prefix.size()) : alone;
    return "tetiso::reduce_batch: piece " + std::to_string(index) + ": " + what;
}

// The piece under test batched, after a piece that finishes in round 0 and
// before an empty piece (test_reduce_batch.cpp has pieces with the same
// keys and more): each result must be the piece's alone, or the error
// reduce() gave it, naming it.
inline void expect_batch_is_alone(const Piece& in, const ReduceOptions& options, const Piece& alone,
                                  const std::string& alone_error) {
    const std::vector<Piece> batch{one_triangle(), in, Piece{}};
    std::string triangle_error;
    Piece triangle_alone;
    try {
        triangle_alone = reduce(batch[0], options);
    } catch (const Error& e) {
        triangle_error = e.what();
    }
    std::vector<Piece> out;
    std::string error;
    try {
        out = reduce_batch(batch, options);
    } catch (const Error& e) {
        error = e.what();
    }
    if (!alone_error.empty()) {
        EXPECT_EQ(error, batch_error_for(alone_error, 1, triangle_error == alone_error));
        return;
    }
    ASSERT_EQ(error, "");
    ASSERT_EQ(out.size(), batch.size());
    EXPECT_TRUE(same_piece(triangle_alone, out[0])) << "the triangle";
    EXPECT_TRUE(same_piece(alone, out[1])) << "the piece";
    EXPECT_TRUE(same_piece(reduce(Piece{}, options), out[2])) << "the empty piece";
}

#ifdef TETISO_TEST_GPU

// One GPU for the whole program: its buffers serve every case in turn, as a
// worker's serve its tasks.
inline const Device& the_gpu() {
    static const Device gpu = Device::cuda();
    return gpu;
}

inline Piece reduce_under_test(const Piece& in, const ReduceOptions& options = {}, ReduceReport* report = nullptr) {
    std::string cpu_error, gpu_error;
    Piece cpu, gpu;
    ReduceReport cpu_report, gpu_report;
    try {
        cpu = reduce(in, options, &cpu_report);
    } catch (const Error& e) {
        cpu_error = e.what();
    }
    ReduceOptions on_gpu = options;
    on_gpu.device = the_gpu();
    try {
        gpu = reduce(in, on_gpu, &gpu_report);
    } catch (const Error& e) {
        gpu_error = e.what();
    }
    EXPECT_EQ(cpu_error, gpu_error);
    expect_batch_is_alone(in, on_gpu, cpu, cpu_error);
    if (!cpu_error.empty()) throw Error(cpu_error);
    EXPECT_TRUE(same_piece(cpu, gpu));
    EXPECT_EQ(cpu_report.rounds.size(), gpu_report.rounds.size());
    for (std::size_t r = 0; r < std::min(cpu_report.rounds.size(), gpu_report.rounds.size()); ++r) {
        EXPECT_EQ(cpu_report.rounds[r].collapses, gpu_report.rounds[r].collapses) << "round " << r;
        EXPECT_EQ(cpu_report.rounds[r].flips, gpu_report.rounds[r].flips) << "round " << r;
    }
    if (report) *report = cpu_report;
    return cpu;
}

// Skips every test of the program where there is no GPU (CI).
class SkipWithoutGpu : public ::testing::Environment {
public:
    void SetUp() override {
        const GpuInfo info = gpu_info();
        if (!info.available) GTEST_SKIP() << "no GPU: " << info.description;
    }
};
inline ::testing::Environment* const kSkipWithoutGpu = ::testing::AddGlobalTestEnvironment(new SkipWithoutGpu);

#else

inline Piece reduce_under_test(const Piece& in, const ReduceOptions& options = {}, ReduceReport* report = nullptr) {
    std::string error;
    Piece out;
    try {
        out = reduce(in, options, report);
    } catch (const Error& e) {
        error = e.what();
    }
    expect_batch_is_alone(in, options, out, error);
    if (!error.empty()) throw Error(error);
    return out;
}

#endif

} // namespace tetiso::test
