// The three ways a force field writes its stiffness must give the same matrix: added to a
// cleared matrix (both off-diagonal blocks and the diagonal gathered per pair and per node),
// set (only the blocks above the diagonal written, then completed row by row from their
// mirrors), and set into the single-precision copy the CG product reads.

#include <gtest/gtest.h>

#include <memory>

#include "hof/mechanics/block_sparse_matrix.h"
#include "hof/mechanics/detail/mesh_spring_force_field.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"
#include "test_meshes.h"

namespace hof::mechanics {
namespace {

// A 3x2x2 box deformed by a non-affine, partly rotating displacement, so that the
// co-rotational blocks are neither symmetric per block nor all alike.
Eigen::VectorXd deformed(const testing::BoxMesh& box) {
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(box.nodes.size()));
  for (std::size_t n = 0; n < box.nodes.size(); ++n) {
    const Vec3& p = box.nodes[n];
    const double angle = 0.4 * p.x() / box.size.x();
    const Vec3 bent(p.x(), std::cos(angle) * p.y() - std::sin(angle) * p.z(),
                    std::sin(angle) * p.y() + std::cos(angle) * p.z());
    x.segment<3>(3 * static_cast<Eigen::Index>(n)) =
        bent + Vec3(0.1 * p.y() * p.y(), 0.05 * p.x() * p.z(), -0.02 * p.x());
  }
  return x;
}

// Dense copy of the single-precision blocks: entry (i, q) of a block at [8q + i].
Eigen::MatrixXd single_to_dense(const BlockSparseMatrix& k) {
  const Eigen::Index n = 3 * static_cast<Eigen::Index>(k.block_rows());
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (std::int32_t r = 0; r < k.block_rows(); ++r) {
    for (std::int64_t s = k.row_start()[r]; s < k.row_start()[r + 1]; ++s) {
      const float* block = k.single_block(s);
      for (int i = 0; i < 3; ++i) {
        for (int q = 0; q < 3; ++q) {
          d(3 * r + i, 3 * k.columns()[s] + q) = block[BlockSparseMatrix::kSingleColumnStride * q + i];
        }
      }
    }
  }
  return d;
}

void expect_targets_agree(ForceField& field, const Eigen::VectorXd& x) {
  std::vector<std::pair<std::int32_t, std::int32_t>> pairs;
  field.collect_couplings(pairs);
  BlockSparseMatrix k = BlockSparseMatrix::from_pairs(static_cast<std::int32_t>(x.size() / 3), pairs);
  field.bind(k);
  k.prepare_single_precision();
  ForceFieldState state = field.make_state();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  field.add_force(x, Eigen::VectorXd::Zero(x.size()), state, f);
  constexpr double kScale = 0.7;

  k.set_zero();
  field.add_stiffness(state, kScale, k);
  const Eigen::MatrixXd added = k.to_dense();
  ASSERT_GT(added.norm(), 0.0);

  // Poison the values first: every block must be overwritten.
  for (std::int64_t v = 0; v < BlockSparseMatrix::kBlockStride * k.block_count(); ++v) k.values()[v] = 1e30;
  ASSERT_TRUE(field.set_stiffness(state, kScale, k));
  const Eigen::MatrixXd set = k.to_dense();
  EXPECT_LT((set - added).norm(), 1e-12 * added.norm());
  EXPECT_LT((set - set.transpose()).norm(), 1e-12 * set.norm());
  // Rigid translations are not loaded: every block row sums to zero.
  for (Eigen::Index r = 0; r < set.rows(); ++r) {
    for (int axis = 0; axis < 3; ++axis) {
      double sum = 0.0;
      for (Eigen::Index c = axis; c < set.cols(); c += 3) sum += set(r, c);
      EXPECT_NEAR(sum, 0.0, 1e-12 * added.norm()) << "row " << r;
    }
  }

  for (std::int64_t s = 0; s < k.block_count(); ++s) {
    for (int q = 0; q < 3; ++q) {
      for (int i = 0; i < 3; ++i) k.single_block(s)[BlockSparseMatrix::kSingleColumnStride * q + i] = 1e30f;
    }
  }
  ASSERT_TRUE(field.set_stiffness_single(state, kScale, k));
  EXPECT_LT((single_to_dense(k) - added).norm(), 1e-6 * added.norm());
}

TEST(StiffnessAssembly, CorotationalFemTargetsAgree) {
  const auto box = testing::box_mesh(3, 2, 2, Vec3(0.03, 0.02, 0.02));
  auto field =
      TetrahedronFemForceField::make(box.nodes, box.tets, {30000.0, 0.45, FemMethod::kLarge, {}, {}}, "tissue");
  ASSERT_TRUE(field.has_value()) << field.error().to_string();
  expect_targets_agree(**field, deformed(box));
}

TEST(StiffnessAssembly, MeshSpringTargetsAgree) {
  const auto box = testing::box_mesh(3, 2, 2, Vec3(0.03, 0.02, 0.02));
  auto field = MeshSpringForceField::make(box.nodes, box.tets, {}, {5000.0, 25.0}, "tissue");
  ASSERT_TRUE(field.has_value()) << field.error().to_string();
  expect_targets_agree(**field, deformed(box));
}

// A patch's force summed from the elements that touch it alone (the FEM-reaction coupling's
// path) equals the whole pass's entries summed over the same nodes, for every rotation method
// and with velocities that load the springs' dampers. A patch both inside the box and on its
// surface, listing a node twice (it must count once).
void expect_patch_sum_agrees(const ForceField& field, const Eigen::VectorXd& x) {
  const Eigen::Index n = x.size() / 3;
  Eigen::VectorXd v(x.size());
  for (Eigen::Index i = 0; i < v.size(); ++i) v[i] = 0.01 * std::sin(0.7 * static_cast<double>(i));
  ForceFieldState state = field.make_state();
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  field.add_force(x, v, state, f);
  const std::vector<std::int32_t> patch{0, 5, 6, 17, 5, static_cast<std::int32_t>(n - 1)};
  std::vector<std::uint8_t> in_set(static_cast<std::size_t>(n), 0);
  Vec3 expected = Vec3::Zero();
  for (const std::int32_t node : patch) {
    if (in_set[static_cast<std::size_t>(node)] == 0) expected += f.segment<3>(3 * static_cast<Eigen::Index>(node));
    in_set[static_cast<std::size_t>(node)] = 1;
  }
  ASSERT_GT(expected.norm(), 0.0);
  std::vector<std::int32_t> scratch;
  Vec3 total = Vec3::Zero();
  ASSERT_TRUE(field.add_force_sum_on(x, v, patch, in_set, scratch, total));
  EXPECT_LT((total - expected).norm(), 1e-12 * f.norm()) << total.transpose() << " vs " << expected.transpose();
  // Every node marked: the internal forces cancel, the sum is that of the whole pass.
  std::fill(in_set.begin(), in_set.end(), std::uint8_t{1});
  std::vector<std::int32_t> all(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::int32_t>(i);
  total.setZero();
  ASSERT_TRUE(field.add_force_sum_on(x, v, all, in_set, scratch, total));
  Vec3 whole = Vec3::Zero();
  for (Eigen::Index i = 0; i < n; ++i) whole += f.segment<3>(3 * i);
  EXPECT_LT((total - whole).norm(), 1e-10 * f.norm());
}

TEST(PatchForceSum, AgreesWithTheWholePass) {
  const auto box = testing::box_mesh(3, 2, 2, Vec3(0.03, 0.02, 0.02));
  const Eigen::VectorXd x = deformed(box);
  for (const FemMethod method : {FemMethod::kSmall, FemMethod::kLarge, FemMethod::kPolar}) {
    SCOPED_TRACE(static_cast<int>(method));
    auto fem = TetrahedronFemForceField::make(box.nodes, box.tets, {30000.0, 0.45, method, {}, {}}, "tissue");
    ASSERT_TRUE(fem.has_value()) << fem.error().to_string();
    expect_patch_sum_agrees(**fem, x);
  }
  auto springs = MeshSpringForceField::make(box.nodes, box.tets, {}, {5000.0, 25.0}, "tissue");
  ASSERT_TRUE(springs.has_value()) << springs.error().to_string();
  expect_patch_sum_agrees(**springs, x);
}

TEST(BlockSparseMatrix, CompleteFromUpperMirrorsAndSumsRows) {
  auto m = BlockSparseMatrix::from_pairs(4, {{0, 1}, {1, 2}, {0, 3}, {2, 3}});
  m.prepare_single_precision();
  for (std::int32_t r = 0; r < 4; ++r) {
    for (std::int64_t s = m.row_start()[r]; s < m.row_start()[r + 1]; ++s) {
      EXPECT_EQ(m.mirror_slot(m.mirror_slot(s)), s);
      if (m.columns()[s] <= r) continue;
      for (int i = 0; i < 3; ++i) {
        for (int q = 0; q < 3; ++q) {
          const double value = static_cast<double>((7 * s + 3 * i + q) % 11) - 5.0;
          m.block(s)(i, q) = value;
          m.single_block(s)[BlockSparseMatrix::kSingleColumnStride * q + i] = static_cast<float>(value);
        }
      }
    }
  }
  m.complete_from_upper(0, 4);
  m.complete_from_upper_single(0, 4);
  const Eigen::MatrixXd d = m.to_dense();
  for (std::int32_t r = 0; r < 4; ++r) {
    for (std::int32_t c = 0; c < r; ++c) {
      EXPECT_EQ((d.block<3, 3>(3 * r, 3 * c) - d.block<3, 3>(3 * c, 3 * r).transpose()).norm(), 0.0);
    }
  }
  ASSERT_GT((d.block<3, 3>(0, 3).norm()), 0.0);
  for (std::int32_t r = 0; r < 4; ++r) {
    Mat3 sum = Mat3::Zero();
    for (std::int32_t c = 0; c < 4; ++c) sum += d.block<3, 3>(3 * r, 3 * c);
    EXPECT_EQ(sum.norm(), 0.0) << "row " << r;
  }
  EXPECT_EQ((single_to_dense(m) - d).norm(), 0.0);
}

}  // namespace
}  // namespace hof::mechanics
