// For tests: the host reduction made to choose as the GPU does (by
// deterministic reservations in every round, the flips too, on any thread
// count), with a window of `window` operations (0: the host's), and tested
// as `speculation` says. Its output must be reduce()'s, byte for byte: the
// choice does not depend on how it is made, and this checks that where there
// is no GPU.
#pragma once

#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::detail {

// When the collapses are tested: each when the steps reach it (the host's
// way), or every one before the steps (speculation, the GPU's way), either
// with every test or with the samples placed only for those the steps decide
// (the GPU's in large rounds).
enum class Speculation { kNone, kEveryTest, kSamplesWhenDecided };

Piece reduce_by_reservations(const Piece& in, const ReduceOptions& options, long window, Speculation speculation,
                             ReduceReport* report = nullptr);

} // namespace tetiso::detail
