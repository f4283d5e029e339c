#pragma once
/// @file
/// The vector passes of the conjugate-gradient solve, each one fused loop over a range of
/// whole nodes (3 doubles per node) with its dot product summed in the same loop. Why fused
/// and hand-vectorised: the textbook form (two axpys, a dot product, a rounding pass) reads
/// every vector several times and, with the pointers the solver passes, the compiler
/// vectorises the loops only behind run-time alias checks; one pass over the data is 2–2.4×
/// faster here (docs/performance.md). Sums are taken in a fixed order within the range, so
/// results depend on the range only, never on which thread runs it.

#include <cstddef>

namespace hof::mechanics::detail {

/// x += α·p and r −= α·ap over nodes [first, last); returns the range's rᵀr (new r). When
/// `r_single` is not null, also writes the new r rounded to single precision in the padded
/// layout of BlockSparseMatrix::round_to_single (4 floats per node, the fourth zero).
/// @pre x, r, p, ap (3 per node) and r_single (4 per node) do not overlap.
double cg_update_solution(double* x, double* r, const double* p, const double* ap, double alpha, float* r_single,
                          std::size_t first, std::size_t last);

/// p = z + β·p and ap = az + β·ap over nodes [first, last); returns the range's pᵀap (new
/// values): the new direction and its product by linearity, A(z + βp) = Az + β·Ap.
/// @pre the arrays (3 per node) do not overlap.
double cg_update_direction(double* p, double* ap, const double* z, const double* az, double beta, std::size_t first,
                           std::size_t last);

}  // namespace hof::mechanics::detail
