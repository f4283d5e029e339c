#include "hof/mechanics/von_mises_stress.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "hof/mechanics/detail/tet_rest_geometry.h"
#include "hof/mechanics/detail/tetrahedron_fem_force_field.h"

namespace hof::mechanics {

double von_mises_from_stretches(const Vec3& stretches, double lambda, double mu) {
  const Vec3 strain = stretches - Vec3::Ones();
  const Vec3 s = Vec3::Constant(lambda * strain.sum()) + 2.0 * mu * strain;
  return std::sqrt(0.5 *
                   ((s[0] - s[1]) * (s[0] - s[1]) + (s[1] - s[2]) * (s[1] - s[2]) + (s[2] - s[0]) * (s[2] - s[0])));
}

VonMisesStress::VonMisesStress(const ModelConfig& config) {
  double young = 0.0, poisson = 0.0;
  const std::vector<double>* per_element = nullptr;
  const std::vector<double>* per_element_poisson = nullptr;
  for (const ForceFieldConfig& f : config.force_fields) {
    if (f.tetrahedron_fem) {
      young = f.tetrahedron_fem->young_modulus_pa;
      poisson = f.tetrahedron_fem->poisson_ratio;
      per_element = &f.tetrahedron_fem->element_young_modulus_pa;
      per_element_poisson = &f.tetrahedron_fem->element_poisson_ratio;
    } else if (f.neo_hookean) {
      young = f.neo_hookean->young_modulus_pa;
      poisson = f.neo_hookean->poisson_ratio;
      per_element = &f.neo_hookean->element_young_modulus_pa;
      per_element_poisson = &f.neo_hookean->element_poisson_ratio;
    } else {
      continue;
    }
    source_ = f.name;
    break;
  }
  if (!per_element || config.tets.empty()) return;
  const auto weights = element_modulus_weights(*per_element, young, config.tets.size(), source_);
  if (!weights) return;  // the model would not build either
  if (!per_element_poisson->empty() && per_element_poisson->size() != config.tets.size()) return;
  node_volume_.assign(config.positions.size(), 0.0);
  elements_.reserve(config.tets.size());
  for (std::size_t t = 0; t < config.tets.size(); ++t) {
    const auto rest = tet_rest_geometry(config.positions, config.tets[t], t, source_);
    if (!rest) {
      elements_.clear();
      return;
    }
    Element e{};
    e.nodes = rest->nodes;
    Mat3 dm;
    for (int c = 0; c < 3; ++c)
      dm.col(c) = config.positions[static_cast<std::size_t>(e.nodes[c + 1])] -
                  config.positions[static_cast<std::size_t>(e.nodes[0])];
    e.rest_inverse = dm.inverse();
    e.volume = rest->volume;
    // A tissue region's own Poisson ratio changes λ/μ, its modulus scales both.
    const double nu =
        per_element_poisson->empty() || (*per_element_poisson)[t] == 0.0 ? poisson : (*per_element_poisson)[t];
    const Lame lame = lame_parameters(young, nu);
    e.lambda = (*weights)[t] * lame.lambda;
    e.mu = (*weights)[t] * lame.mu;
    for (const std::int32_t n : e.nodes) node_volume_[static_cast<std::size_t>(n)] += e.volume;
    elements_.push_back(e);
  }
}

void VonMisesStress::element_stress(std::span<const double> x, std::vector<double>& out) const {
  out.assign(elements_.size(), 0.0);
  if (x.size() < 3 * node_volume_.size()) return;
  for (std::size_t i = 0; i < elements_.size(); ++i) {
    const Element& e = elements_[i];
    const auto at = [&](std::int32_t n) {
      return Vec3(x[3 * static_cast<std::size_t>(n)], x[3 * static_cast<std::size_t>(n) + 1],
                  x[3 * static_cast<std::size_t>(n) + 2]);
    };
    const Vec3 x0 = at(e.nodes[0]);
    Mat3 ds;
    for (int c = 0; c < 3; ++c) ds.col(c) = at(e.nodes[c + 1]) - x0;
    const Mat3 f = ds * e.rest_inverse;
    // Principal stretches: square roots of the eigenvalues of C = FᵀF (the corotated strain
    // S − I of F = RS has the same principal values as these minus one).
    Eigen::SelfAdjointEigenSolver<Mat3> eig;
    eig.computeDirect(f.transpose() * f, Eigen::EigenvaluesOnly);
    const Vec3 stretches = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
    out[i] = von_mises_from_stretches(stretches, e.lambda, e.mu);
  }
}

void VonMisesStress::node_stress(std::span<const double> x, std::vector<double>& out) const {
  element_stress(x, scratch_);
  out.assign(node_volume_.size(), 0.0);
  for (std::size_t i = 0; i < elements_.size(); ++i) {
    for (const std::int32_t n : elements_[i].nodes)
      out[static_cast<std::size_t>(n)] += elements_[i].volume * scratch_[i];
  }
  for (std::size_t n = 0; n < out.size(); ++n) {
    if (node_volume_[n] > 0.0) out[n] /= node_volume_[n];
  }
}

}  // namespace hof::mechanics
