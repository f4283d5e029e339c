#pragma once
// The liver both coupling tests press on: co-rotational FEM (E = 5.4 kPa, ν = 0.45),
// 1060 kg/m³, no gravity, resting on its lowest centimetre (held in a box).

#include <utility>

#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/mesh.h"

namespace hof::coupling::testing {

inline mechanics::ModelConfig resting_liver_config(const mesh::Mesh& liver) {
  mechanics::ModelConfig c;
  c.name = "liver";
  c.positions = liver.nodes;
  c.tets = liver.tets;
  c.mass.kind = mechanics::MassKind::kDiagonal;
  c.mass.mass_density_kg_per_m3 = 1060.0;
  c.gravity_m_per_s2 = Vec3::Zero();
  mechanics::ForceFieldConfig fem;
  fem.name = "FEM";
  fem.tetrahedron_fem = mechanics::TetrahedronFemConfig{5400.0, 0.45, mechanics::FemMethod::kLarge, {}, {}};
  c.force_fields.push_back(fem);
  mechanics::FixedConstraintConfig base;
  base.name = "base";
  base.box = std::make_pair(Vec3(-1, -1, -1), Vec3(1, 1, -0.025));
  c.fixed.push_back(base);
  return c;
}

}  // namespace hof::coupling::testing
