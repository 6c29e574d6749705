// For tests: the host reduction made to choose as the GPU does (by
// deterministic reservations in every round, the flips too, on any thread
// count), with a window of `window` operations (0: the host's), and with
// speculate, every collapse tested before the steps as the GPU does. Its
// output must be reduce()'s, byte for byte: the choice does not depend on how
// it is made, and this checks that where there is no GPU.
#pragma once

#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso::detail {

Piece reduce_by_reservations(const Piece& in, const ReduceOptions& options, long window, bool speculate,
                             ReduceReport* report = nullptr);

} // namespace tetiso::detail
