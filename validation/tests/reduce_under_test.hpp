// The reduction a suite tests. In the suite's GPU build (TETISO_TEST_GPU,
// label gpu) every call runs on the GPU too, whose piece, or error message,
// must be the CPU's byte for byte, and whose rounds choose the same number
// of collapses and flips; where there is no GPU that build skips. So every
// case of the CPU suite is a case of the GPU's, with its own assertions.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "test_support.hpp"
#include "tetiso/error.hpp"
#include "tetiso/reduce.hpp"

#ifdef TETISO_TEST_GPU
#include "tetiso/device.hpp"
#endif

namespace tetiso::test {

#ifdef TETISO_TEST_GPU

// One GPU for the whole program: its buffers serve every case in turn, as a
// worker's serve its tasks.
inline const Device& the_gpu() {
    static const Device gpu = Device::cuda();
    return gpu;
}

// Names the first array that differs.
inline ::testing::AssertionResult same_piece(const Piece& cpu, const Piece& gpu) {
    const auto differ = [](const char* what) { return ::testing::AssertionFailure() << what << " differ"; };
    if (cpu.key != gpu.key) return differ("keys");
    if (!same_bits(cpu.x, gpu.x) || !same_bits(cpu.y, gpu.y) || !same_bits(cpu.z, gpu.z)) return differ("positions");
    if (cpu.flags != gpu.flags) return differ("flags");
    if (cpu.triangles != gpu.triangles) return differ("triangles");
    if (!same_bits(cpu.error, gpu.error)) return differ("error bounds");
    if (!same_bits(cpu.sample_xyz, gpu.sample_xyz) || cpu.sample_triangle != gpu.sample_triangle ||
        cpu.sampled != gpu.sampled)
        return differ("samples");
    if (cpu.domains != gpu.domains) return differ("domain lists");
    return ::testing::AssertionSuccess();
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
    try {
        ReduceOptions on_gpu = options;
        on_gpu.device = the_gpu();
        gpu = reduce(in, on_gpu, &gpu_report);
    } catch (const Error& e) {
        gpu_error = e.what();
    }
    EXPECT_EQ(cpu_error, gpu_error);
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
    return reduce(in, options, report);
}

#endif

} // namespace tetiso::test
