// The extraction a suite tests. In the suite's GPU build (TETISO_TEST_GPU,
// label gpu) every call runs on the GPU too, whose piece, or error message,
// must be the CPU's byte for byte; where there is no GPU that build skips
// (reduce_under_test.hpp). So every case of the CPU suite is a case of the
// GPU's, with its own assertions.
#pragma once

#include <string>

#include <gtest/gtest.h>

#include "reduce_under_test.hpp"
#include "tetiso/error.hpp"
#include "tetiso/extract.hpp"

namespace tetiso::test {

inline Piece extract_under_test(const Domain& domain, float level, const ExtractOptions& options = {}) {
#ifdef TETISO_TEST_GPU
    std::string cpu_error, gpu_error;
    Piece cpu, gpu;
    try {
        cpu = extract(domain, level, options);
    } catch (const Error& e) {
        cpu_error = e.what();
    }
    try {
        ExtractOptions on_gpu = options;
        on_gpu.device = the_gpu();
        gpu = extract(domain, level, on_gpu);
    } catch (const Error& e) {
        gpu_error = e.what();
    }
    EXPECT_EQ(cpu_error, gpu_error);
    if (!cpu_error.empty()) throw Error(cpu_error);
    EXPECT_TRUE(same_piece(cpu, gpu));
    return cpu;
#else
    return extract(domain, level, options);
#endif
}

} // namespace tetiso::test
