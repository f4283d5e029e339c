#include "hof/mechanics/detail/cg_kernels.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "hof/mechanics/block_sparse_matrix.h"

namespace hof::mechanics::detail {
namespace {

// Deterministic values of varied sign and magnitude.
std::vector<double> values(std::size_t n, double seed) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i)
    v[i] = std::sin(seed + 1.7 * static_cast<double>(i)) * std::pow(10.0, static_cast<double>(i % 5) - 2.0);
  return v;
}

// Node ranges that start and end off the kernels' four-node stride, and whole arrays.
struct Range {
  std::size_t nodes, first, last;
};
// Lengths 0–11 and 23: every tail after the four-node steps (0, 1, 2 and 3 nodes).
const Range kRanges[] = {{0, 0, 0}, {1, 0, 1}, {3, 0, 3},   {4, 0, 4},   {6, 0, 6},
                         {7, 0, 7}, {9, 2, 9}, {10, 0, 10}, {13, 1, 12}, {29, 3, 26}};

TEST(CgKernels, UpdateSolutionMatchesTheTextbookLoops) {
  for (const Range& range : kRanges) {
    const std::size_t dofs = 3 * range.nodes;
    const auto p = values(dofs, 0.1), ap = values(dofs, 0.2);
    auto x = values(dofs, 0.3), r = values(dofs, 0.4);
    auto x_ref = x, r_ref = r;
    std::vector<float> r_single(4 * range.nodes + 4, -7.0f), r_single_ref(4 * range.nodes + 4, -7.0f);
    const double alpha = 0.37;
    double rr_ref = 0.0;
    for (std::size_t d = 3 * range.first; d < 3 * range.last; ++d) {
      x_ref[d] += alpha * p[d];
      r_ref[d] -= alpha * ap[d];
      rr_ref += r_ref[d] * r_ref[d];
    }
    BlockSparseMatrix::round_to_single(r_ref.data(), r_single_ref.data(), range.first, range.last);
    const double rr =
        cg_update_solution(x.data(), r.data(), p.data(), ap.data(), alpha, r_single.data(), range.first, range.last);
    for (std::size_t d = 0; d < dofs; ++d) {
      // Fused multiply-adds may round the last bit differently; outside the range nothing moves.
      EXPECT_NEAR(x[d], x_ref[d], 1e-15 * (1.0 + std::abs(x_ref[d]))) << "dof " << d;
      EXPECT_NEAR(r[d], r_ref[d], 1e-15 * (1.0 + std::abs(r_ref[d]))) << "dof " << d;
    }
    EXPECT_NEAR(rr, rr_ref, 1e-13 * (1.0 + rr_ref)) << range.nodes << " nodes";
    // The rounded residual has the padded layout (x y z 0), only for the range's nodes.
    for (std::size_t k = 0; k < r_single.size(); ++k) {
      EXPECT_NEAR(r_single[k], r_single_ref[k], 1e-7f * (1.0f + std::abs(r_single_ref[k]))) << "float " << k;
    }
    // Without a rounded copy requested, the same update.
    auto x2 = values(dofs, 0.3), r2 = values(dofs, 0.4);
    EXPECT_EQ(cg_update_solution(x2.data(), r2.data(), p.data(), ap.data(), alpha, nullptr, range.first, range.last),
              rr);
    EXPECT_EQ(x2, x);
    EXPECT_EQ(r2, r);
  }
}

TEST(CgKernels, UpdateDirectionMatchesTheTextbookLoops) {
  for (const Range& range : kRanges) {
    const std::size_t dofs = 3 * range.nodes;
    const auto z = values(dofs, 1.1), az = values(dofs, 1.2);
    auto p = values(dofs, 1.3), ap = values(dofs, 1.4);
    auto p_ref = p, ap_ref = ap;
    const double beta = -0.61;
    double pap_ref = 0.0;
    for (std::size_t d = 3 * range.first; d < 3 * range.last; ++d) {
      p_ref[d] = z[d] + beta * p_ref[d];
      ap_ref[d] = az[d] + beta * ap_ref[d];
      pap_ref += p_ref[d] * ap_ref[d];
    }
    const double pap = cg_update_direction(p.data(), ap.data(), z.data(), az.data(), beta, range.first, range.last);
    for (std::size_t d = 0; d < dofs; ++d) {
      EXPECT_NEAR(p[d], p_ref[d], 1e-15 * (1.0 + std::abs(p_ref[d]))) << "dof " << d;
      EXPECT_NEAR(ap[d], ap_ref[d], 1e-15 * (1.0 + std::abs(ap_ref[d]))) << "dof " << d;
    }
    EXPECT_NEAR(pap, pap_ref, 1e-13 * (1.0 + std::abs(pap_ref))) << range.nodes << " nodes";
  }
}

TEST(CgKernels, SumsDoNotDependOnWhereTheDataLies) {
  // The same values at addresses shifted by one double give the same bits: a loop that
  // peeled iterations to reach an aligned address would sum in another order, and results
  // would then depend on allocation, not only on the range.
  const std::size_t nodes = 23, dofs = 3 * nodes;
  const auto p = values(dofs, 2.1), ap = values(dofs, 2.2), x0 = values(dofs, 2.3), r0 = values(dofs, 2.4);
  double sums[2][2];
  for (std::size_t shift = 0; shift < 2; ++shift) {
    std::vector<double> buffer(4 * (dofs + 2));
    double* ps = buffer.data() + shift;
    double* aps = ps + dofs + 2;
    double* xs = aps + dofs + 2;
    double* rs = xs + dofs + 2;
    std::copy(p.begin(), p.end(), ps);
    std::copy(ap.begin(), ap.end(), aps);
    std::copy(x0.begin(), x0.end(), xs);
    std::copy(r0.begin(), r0.end(), rs);
    sums[shift][0] = cg_update_solution(xs, rs, ps, aps, 0.5, nullptr, 0, nodes);
    sums[shift][1] = cg_update_direction(ps, aps, rs, xs, 0.25, 0, nodes);
  }
  EXPECT_EQ(sums[0][0], sums[1][0]);
  EXPECT_EQ(sums[0][1], sums[1][1]);
}

}  // namespace
}  // namespace hof::mechanics::detail
