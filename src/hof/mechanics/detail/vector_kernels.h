#pragma once
/// @file
/// Deterministic parallel vector kernels shared by every stage of a step (forces, solve,
/// integration): the results do not depend on the thread count.

#include <Eigen/Core>

#include <cstddef>
#include <vector>

#include "hof/mechanics/mechanical_model.h"

namespace hof::mechanics::detail {

/// Σ a[d]·b[d] over [d0, d1), in a fixed order.
double dot_range(const double* a, const double* b, std::size_t d0, std::size_t d1);
double dot(const Eigen::VectorXd& a, const Eigen::VectorXd& b, std::vector<double>& partials);
/// y += alpha·x
void axpy(double alpha, const Eigen::VectorXd& x, Eigen::VectorXd& y);
/// Zeroes the entries of fixed nodes.
void project(const MechanicalModel& model, Eigen::VectorXd& vector);

}  // namespace hof::mechanics::detail
