// The vector kernels every stage of a step shares (detail/vector_kernels.cpp): their sums
// against a long-double reference, and results that do not depend on the thread count (the
// promise that lets a run be repeated bit for bit on any machine).

#include "hof/mechanics/detail/vector_kernels.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <random>
#include <vector>

namespace hof::mechanics::detail {
namespace {

Eigen::VectorXd random_vector(Eigen::Index n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double mantissa = u(rng);
    const double exponent = u(rng);
    v[i] = mantissa * std::pow(10.0, 3.0 * exponent);  // values over six decades
  }
  return v;
}

long double reference_dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  long double s = 0.0L;
  for (Eigen::Index i = 0; i < a.size(); ++i) s += static_cast<long double>(a[i]) * static_cast<long double>(b[i]);
  return s;
}

TEST(VectorKernels, DotRangeIsTheSumOfProductsOverItsRange) {
  const Eigen::VectorXd a = random_vector(37, 1);
  const Eigen::VectorXd b = random_vector(37, 2);
  long double expected = 0.0L;
  for (int i = 5; i < 30; ++i) expected += static_cast<long double>(a[i]) * b[i];
  EXPECT_NEAR(dot_range(a.data(), b.data(), 5, 30), static_cast<double>(expected), 1e-12 * std::abs(double(expected)));
  EXPECT_EQ(dot_range(a.data(), b.data(), 9, 9), 0.0);
}

TEST(VectorKernels, DotMatchesALongDoubleSumAndDoesNotDependOnTheThreadCount) {
  // Long enough to be cut into many chunks that run in parallel.
  const Eigen::VectorXd a = random_vector(300001, 3);
  const Eigen::VectorXd b = random_vector(300001, 4);
  std::vector<double> partials;
  double one_thread = 0.0, two_threads = 0.0, four_threads = 0.0;
  tbb::task_arena(1).execute([&] { one_thread = dot(a, b, partials); });
  tbb::task_arena(2).execute([&] { two_threads = dot(a, b, partials); });
  tbb::task_arena(4).execute([&] { four_threads = dot(a, b, partials); });
  EXPECT_EQ(one_thread, two_threads);
  EXPECT_EQ(one_thread, four_threads);
  const long double expected = reference_dot(a, b);
  long double magnitude = 0.0L;
  for (Eigen::Index i = 0; i < a.size(); ++i) magnitude += std::abs(static_cast<long double>(a[i]) * b[i]);
  EXPECT_LE(std::abs(static_cast<long double>(one_thread) - expected), 1e-13L * magnitude);
}

TEST(VectorKernels, AxpyAddsTheScaledVectorEntryByEntry) {
  const Eigen::VectorXd x = random_vector(200003, 5);
  Eigen::VectorXd y = random_vector(200003, 6);
  const Eigen::VectorXd before = y;
  tbb::task_arena(2).execute([&] { axpy(-0.75, x, y); });
  // Within an ulp or two: a compiler may fuse the multiply-add (FMA) in the kernel or here.
  for (Eigen::Index i = 0; i < y.size(); ++i) {
    const double expected = before[i] + -0.75 * x[i];
    ASSERT_NEAR(y[i], expected, 4e-16 * (std::abs(before[i]) + std::abs(0.75 * x[i]))) << i;
  }
}

}  // namespace
}  // namespace hof::mechanics::detail
