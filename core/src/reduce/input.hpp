// The checks every reduction makes before any work, whichever device runs it.
#pragma once

#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso {

// Throws tetiso::Error for input that breaks reduce()'s rules (reduce.hpp),
// naming the element.
void check_reduce_input(const Piece& in);

// Throws tetiso::Error for an option outside its valid range.
void check_reduce_options(const ReduceOptions& options);

} // namespace tetiso
