#pragma once
/// @file
/// Writing one 3x3 stiffness block, given as three columns of four lanes (the fourth zero),
/// into a BlockSparseMatrix: added to the double values, set in them, or set in the
/// single-precision copy. Shared by the force fields that sum each block in registers.

#include <cstdint>

#include "hof/mechanics/block_sparse_matrix.h"
#include "hof/mechanics/detail/simd_lanes.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace hof::mechanics {

enum class StiffnessTarget : std::uint8_t { kAddDouble, kSetDouble, kSetSingle };

template <StiffnessTarget kTarget>
inline void write_block(BlockSparseMatrix& k, std::int64_t slot, simd::Lanes col0, simd::Lanes col1, simd::Lanes col2) {
  if constexpr (kTarget == StiffnessTarget::kSetSingle) {
    float* block = k.single_block(slot);
    simd::store_single(block, col0);
    simd::store_single(block + BlockSparseMatrix::kSingleColumnStride, col1);
    simd::store_single(block + 2 * BlockSparseMatrix::kSingleColumnStride, col2);
  } else {
    double* block = k.values() + BlockSparseMatrix::kBlockStride * slot;
    if constexpr (kTarget == StiffnessTarget::kAddDouble) {
      col0 += simd::load(block);
      col1 += simd::load(block + 4);
      col2 += simd::load(block + 8);
    }
    simd::store(block, col0);
    simd::store(block + 4, col1);
    simd::store(block + 8, col2);
  }
}

}  // namespace hof::mechanics

#pragma GCC diagnostic pop
