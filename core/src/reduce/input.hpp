// The checks every reduction makes before any work, whichever device runs it.
#pragma once

#include <cstddef>
#include <vector>

#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"
#include "tetiso/reduce.hpp"

namespace tetiso {

// Throws tetiso::Error for input that breaks reduce()'s rules (reduce.hpp),
// naming the element.
void check_reduce_input(const Piece& in);

// Throws tetiso::Error for an option outside its valid range.
void check_reduce_options(const ReduceOptions& options);

// check_reduce_input for every piece of a batch; the error names the piece.
void check_batch_input(const std::vector<Piece>& pieces);

// reduce()'s error for a piece of a batch, naming the piece.
Error batch_error(std::size_t piece, const Error& e);

} // namespace tetiso
