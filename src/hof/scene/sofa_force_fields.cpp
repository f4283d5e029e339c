#include <algorithm>
#include <cmath>
#include <map>

#include "hof/scene/sofa_scene_reader.h"

// Maps a model node's force fields (elastic lists, FEM, springs, constant forces) to mechanics
// configs (SOFA names and defaults from sofa-components.md). The node itself, its solvers,
// mass, grid, constraints and visuals are in sofa_scene_model.cpp.

namespace hof::scene::detail {

// youngModulus and poissonRatio of a linear-elastic field: one value, or (SOFA's vector form)
// one per element. A list's most common value becomes the field's own (what a user tunes);
// elements that differ keep theirs (0 in the per-element list: the field's value).
Expected<void> Reader::elastic_lists(Component& c, double default_young, double default_poisson, std::size_t elements,
                                     const char* element_name, double& young, std::vector<double>& young_list,
                                     double& poisson, std::vector<double>& poisson_list) {
  const auto read = [&](const char* key, double fallback, double& value, std::vector<double>& list, const auto& valid,
                        const char* range) -> Expected<void> {
    value = fallback;
    const std::string* text = c.attr(key);
    if (!text) return {};
    auto values = numbers(c, key, *text);
    if (!values) return std::unexpected(values.error());
    if (values->empty()) return fail(c, fmt::format("attribute {}: empty, expected a number", key));
    if (!std::ranges::all_of(*values, valid)) {
      return fail(c, fmt::format("attribute {}: every value must be {}", key, range), ErrorCode::kInvalidArgument);
    }
    value = values->front();
    if (std::ranges::all_of(*values, [&](double v) { return v == values->front(); })) return {};
    if (values->size() != elements) {
      return fail(c,
                  fmt::format("attribute {}: {} values; one per {} ({}) or a single one", key, values->size(),
                              element_name, elements),
                  ErrorCode::kInvalidArgument);
    }
    std::map<double, std::size_t> counts;
    for (const double v : *values) ++counts[v];
    value = std::ranges::max_element(counts, {}, [](const auto& kv) { return kv.second; })->first;
    list.reserve(values->size());
    for (const double v : *values) list.push_back(v == value ? 0.0 : v);
    return {};
  };
  if (auto r = read(
          "youngModulus", default_young, young, young_list, [](double v) { return v > 0.0 && std::isfinite(v); },
          "> 0 Pa");
      !r) {
    return r;
  }
  return read(
      "poissonRatio", default_poisson, poisson, poisson_list, [](double v) { return v > -1.0 && v < 0.5; },
      "in (-1, 0.5)");
}

// A force field of the node: its config made by the function of its type (below).
Expected<void> Reader::apply_force_field(Component& c, ModelConfig& m) {
  c.used = true;
  mechanics::ForceFieldConfig ff;
  ff.name = c.name;
  const auto take = [&](auto made, auto& to) -> Expected<void> {
    if (!made) return std::unexpected(made.error());
    to = std::move(*made);
    return {};
  };
  Expected<void> r;
  if (c.type == "TetrahedronFEMForceField" || c.type == "FastTetrahedralCorotationalForceField") {
    r = take(tetrahedron_fem_config(c, m), ff.tetrahedron_fem);
  } else if (c.type == "TetrahedronHyperelasticityFEMForceField") {
    r = take(neo_hookean_config(c), ff.neo_hookean);
  } else if (c.type == "HexahedronFEMForceField" || c.type == "HexahedralFEMForceField") {
    r = take(hexahedron_fem_config(c, m), ff.hexahedron_fem);
  } else if (c.type == "TriangleFEMForceField" || c.type == "TriangularFEMForceField") {
    r = take(triangle_fem_config(c, m), ff.triangle_fem);
  } else if (c.type == "MeshSpringForceField") {
    r = take(mesh_springs_config(c), ff.mesh_springs);
  } else {  // ConstantForceField
    r = take(constant_force_config(c, m), ff.constant_force);
  }
  if (!r) return r;
  m.force_fields.push_back(std::move(ff));
  return {};
}

// TetrahedronFEMForceField (and FastTetrahedralCorotationalForceField, the same law).
Expected<mechanics::TetrahedronFemConfig> Reader::tetrahedron_fem_config(Component& c, const ModelConfig& m) {
  mechanics::TetrahedronFemConfig fem;
  if (auto r = elastic_lists(c, 5000.0, 0.45, m.tets.size(), "tetrahedron", fem.young_modulus_pa,
                             fem.element_young_modulus_pa, fem.poisson_ratio, fem.element_poisson_ratio);
      !r) {
    return std::unexpected(r.error());
  }
  const std::string method = c.attr("method") ? lower(std::string(trim(*c.attr("method")))) : std::string("large");
  if (method == "small" || method == "none")
    fem.method = mechanics::FemMethod::kSmall;
  else if (method == "large" || method == "qr")
    fem.method = mechanics::FemMethod::kLarge;
  else if (method == "polar" || method == "polar2")
    fem.method = mechanics::FemMethod::kPolar;
  else if (method == "svd") {
    fem.method = mechanics::FemMethod::kPolar;
    warn(c.line, fmt::format("{}: method svd simulated as polar (same rotation away from inversion)", c.label()));
  } else {
    return fail(c, fmt::format("attribute method: '{}' is not small, large, polar or svd", method));
  }
  if (c.written != c.type) warn(c.line, fmt::format("{}: read as TetrahedronFEMForceField", c.label()));
  return fem;
}

Expected<mechanics::NeoHookeanConfig> Reader::neo_hookean_config(Component& c) {
  // SOFA's NeoHookean takes ParameterSet = [μ, k] (shear and bulk moduli). HoF's Neo-Hookean
  // (neo_hookean_force_field.h) is the compressible form with λ = k − 2μ/3: the same small-
  // strain response (E = 9kμ/(3k + μ), ν = (3k − 2μ)/(2(3k + μ))), a different volumetric term.
  const std::string material =
      c.attr("materialName") ? std::string(trim(*c.attr("materialName"))) : std::string("ArrudaBoyce");
  if (material != "NeoHookean") {
    return fail(c,
                fmt::format("materialName '{}': HoF simulates NeoHookean (and the linear and co-rotational "
                            "TetrahedronFEMForceField)",
                            material),
                ErrorCode::kUnsupported);
  }
  const std::string* text = c.attr("ParameterSet");
  if (!text) return fail(c, "NeoHookean needs ParameterSet=\"mu k\" (shear and bulk moduli, Pa)");
  auto values = numbers(c, "ParameterSet", *text);
  if (!values) return std::unexpected(values.error());
  if (values->size() != 2)
    return fail(c, fmt::format("attribute ParameterSet: NeoHookean takes 2 values (mu k), got {}", values->size()));
  const double mu = (*values)[0], bulk = (*values)[1];
  if (!(mu > 0.0) || !(bulk > 2.0 * mu / 3.0) || !std::isfinite(bulk)) {
    return fail(c,
                fmt::format("attribute ParameterSet: needs mu > 0 and k > 2mu/3 (a Poisson ratio above 0), got {} {}",
                            mu, bulk),
                ErrorCode::kInvalidArgument);
  }
  mechanics::NeoHookeanConfig neo;
  neo.young_modulus_pa = 9.0 * bulk * mu / (3.0 * bulk + mu);
  neo.poisson_ratio = (3.0 * bulk - 2.0 * mu) / (2.0 * (3.0 * bulk + mu));
  warn(c.line, fmt::format("{}: read as HoF's compressible Neo-Hookean with E = {:.6g} Pa, nu = {:.6g}", c.label(),
                           neo.young_modulus_pa, neo.poisson_ratio));
  return neo;
}

// HexahedronFEMForceField (and HexahedralFEMForceField) on the grid of the node.
Expected<mechanics::HexahedronFemConfig> Reader::hexahedron_fem_config(Component& c, const ModelConfig& m) {
  if (m.hexahedra.empty())
    return fail(c, "no hexahedra in the node (give it a RegularGridTopology or SparseGridTopology)");
  mechanics::HexahedronFemConfig fem;
  if (auto r = elastic_lists(c, 5000.0, 0.45, m.hexahedra.size(), "hexahedron", fem.young_modulus_pa,
                             fem.element_young_modulus_pa, fem.poisson_ratio, fem.element_poisson_ratio);
      !r) {
    return std::unexpected(r.error());
  }
  const std::string method = c.attr("method") ? lower(std::string(trim(*c.attr("method")))) : std::string("large");
  if (method == "small")
    fem.method = mechanics::FemMethod::kSmall;
  else if (method == "large")
    fem.method = mechanics::FemMethod::kLarge;
  else if (method == "polar")
    fem.method = mechanics::FemMethod::kPolar;
  else
    return fail(c, fmt::format("attribute method: '{}' is not small, large or polar", method));
  if (c.type != "HexahedronFEMForceField") warn(c.line, fmt::format("{}: read as HexahedronFEMForceField", c.label()));
  return fem;
}

// TriangleFEMForceField and TriangularFEMForceField: a membrane on a surface model.
Expected<mechanics::TriangleFemConfig> Reader::triangle_fem_config(Component& c, const ModelConfig& m) {
  if (!m.tets.empty()) {
    return fail(c,
                fmt::format("a membrane on a tetrahedral body: HoF simulates {} on a node whose topology has "
                            "triangles and no tetrahedra (a surface model)",
                            c.type),
                ErrorCode::kUnsupported);
  }
  if (m.triangles.empty()) return fail(c, "no triangles in the node (give it a triangle topology or a surface loader)");
  mechanics::TriangleFemConfig fem;
  fem.sofa_type = c.type;
  // SOFA's defaults differ: TriangleFEMForceField E = 1000, ν = 0.3; TriangularFEMForceField
  // (BaseLinearElasticityFEMForceField) E = 5000, ν = 0.45.
  const bool triangular = c.type == "TriangularFEMForceField";
  if (auto r = elastic_lists(c, triangular ? 5000.0 : 1000.0, triangular ? 0.45 : 0.3, m.triangles.size(), "triangle",
                             fem.young_modulus_pa, fem.element_young_modulus_pa, fem.poisson_ratio,
                             fem.element_poisson_ratio);
      !r) {
    return std::unexpected(r.error());
  }
  auto thickness = number(c, "thickness");
  if (!thickness) return std::unexpected(thickness.error());
  fem.thickness_m = thickness->value_or(1.0);
  if (!(fem.thickness_m > 0.0))
    return fail(c, fmt::format("attribute thickness: must be > 0, got {}", fem.thickness_m),
                ErrorCode::kInvalidArgument);
  auto rest_scale = number(c, "restScale");
  if (!rest_scale) return std::unexpected(rest_scale.error());
  fem.rest_scale = rest_scale->value_or(1.0);
  if (!(fem.rest_scale > 0.0 && fem.rest_scale <= 2.0)) {
    return fail(c, fmt::format("attribute restScale: must be in (0, 2], got {}", fem.rest_scale),
                ErrorCode::kInvalidArgument);
  }
  if (const std::string* plane = c.attr("planeStrain")) {
    const std::string v = lower(std::string(trim(*plane)));
    fem.plane_strain = v == "1" || v == "true";
  }
  const std::string method = c.attr("method") ? lower(std::string(trim(*c.attr("method")))) : std::string("large");
  if (method == "small")
    fem.method = mechanics::FemMethod::kSmall;
  else if (method == "large")
    fem.method = mechanics::FemMethod::kLarge;
  else
    return fail(c, fmt::format("attribute method: '{}' is not small or large", method));
  return fem;
}

Expected<mechanics::MeshSpringConfig> Reader::mesh_springs_config(Component& c) {
  // SOFA's MeshSpringForceField (MeshSpringForceField::init, addSpring): one spring per unique
  // edge, its stiffness and damping the element kind's value divided by its rest length,
  // kinds taken in the order lines, triangles, quads, tetrahedra, cubes (the first kind with
  // the edge and a non-zero value sets it); `stiffness`/`damping` set every kind. Its tangent
  // is SpringForceField's, unclamped.
  mechanics::MeshSpringConfig s;
  s.rule = mechanics::SpringStiffnessRule::kDividedByRestLength;
  s.tangent = mechanics::SpringTangent::kExact;
  auto k = number(c, "stiffness");
  auto d = number(c, "damping");
  if (!k) return std::unexpected(k.error());
  if (!d) return std::unexpected(d.error());
  s.stiffness_n_per_m = k->value_or(0.0);
  s.damping_n_s_per_m = d->value_or(0.0);
  const auto kind = [&](const char* ks, const char* kd, const char* old_ks,
                        const char* old_kd) -> Expected<std::optional<mechanics::SpringValues>> {
    auto kk = number(c, c.attr(ks) || !old_ks ? ks : old_ks);
    auto dd = number(c, c.attr(kd) || !old_kd ? kd : old_kd);
    if (!kk) return std::unexpected(kk.error());
    if (!dd) return std::unexpected(dd.error());
    if (!*kk && !*dd) return std::optional<mechanics::SpringValues>{};
    return std::optional<mechanics::SpringValues>{mechanics::SpringValues{kk->value_or(0.0), dd->value_or(0.0)}};
  };
  auto triangles = kind("trianglesStiffness", "trianglesDamping", nullptr, nullptr);
  auto tetrahedra = kind("tetrahedraStiffness", "tetrahedraDamping", "tetrasStiffness", "tetrasDamping");
  if (!triangles) return std::unexpected(triangles.error());
  if (!tetrahedra) return std::unexpected(tetrahedra.error());
  s.triangles = *triangles;
  s.tetrahedra = *tetrahedra;
  // HoF's model has the edges of its triangles and tetrahedra; SOFA's lines, quads and cubes
  // kinds add springs HoF does not have.
  for (const char* key : {"linesStiffness", "quadsStiffness", "cubesStiffness"}) {
    auto v = number(c, key);
    if (!v) return std::unexpected(v.error());
    if (*v && **v != 0.0)
      warn(c.line,
           fmt::format("{}: {} ignored (HoF's springs are the edges of the triangles and tetrahedra)", c.label(), key));
  }
  if (s.stiffness_n_per_m == 0.0 && s.damping_n_s_per_m == 0.0 && !s.triangles && !s.tetrahedra)
    warn(c.line, fmt::format("{}: no stiffness set (SOFA's default 0): the springs hold nothing", c.label()));
  if (auto r = spring_rule_extensions(c, s); !r) return std::unexpected(r.error());
  return s;
}

// HoF extensions (docs/mechanics.md): HoF's own spring rule — the same stiffness for every
// spring, the transverse tangent clamped — which its generated bodies (X3D DeformableShape,
// `hof bench`'s spring cells) use. SOFA's rule stays the default.
Expected<void> Reader::spring_rule_extensions(Component& c, mechanics::MeshSpringConfig& s) {
  if (const std::string* rule = c.attr("stiffnessRule")) {
    const std::string v(trim(*rule));
    if (v == "sameForEverySpring")
      s.rule = mechanics::SpringStiffnessRule::kSameForEverySpring;
    else if (v == "dividedByRestLength")
      s.rule = mechanics::SpringStiffnessRule::kDividedByRestLength;
    else
      return fail(c, fmt::format("attribute stiffnessRule: '{}' is not dividedByRestLength or sameForEverySpring", v));
  }
  if (const std::string* tangent = c.attr("tangent")) {
    const std::string v(trim(*tangent));
    if (v == "clampedTransverse")
      s.tangent = mechanics::SpringTangent::kClampedTransverse;
    else if (v == "exact")
      s.tangent = mechanics::SpringTangent::kExact;
    else
      return fail(c, fmt::format("attribute tangent: '{}' is not exact or clampedTransverse", v));
  }
  return {};
}

// ConstantForceField: forces on some nodes (all by default), or a total spread over them.
Expected<mechanics::ConstantForceConfig> Reader::constant_force_config(Component& c, const ModelConfig& m) {
  mechanics::ConstantForceConfig f;
  auto idx = indices(c, "indices");
  if (!idx) return std::unexpected(idx.error());
  if (*idx)
    f.indices = **idx;
  else
    for (std::int32_t i = 0; i < static_cast<std::int32_t>(m.positions.size()); ++i) f.indices.push_back(i);
  const char* key = c.attr("forces") ? "forces" : "force";
  if (const std::string* text = c.attr(key)) {
    auto v = numbers(c, key, *text);
    if (!v) return std::unexpected(v.error());
    if (v->size() % 3 != 0 || v->empty()) return fail(c, fmt::format("attribute {}: not a list of 3D vectors", key));
    for (std::size_t i = 0; i < v->size(); i += 3) f.forces.emplace_back((*v)[i], (*v)[i + 1], (*v)[i + 2]);
  }
  auto total = vec3(c, "totalForce");
  if (!total) return std::unexpected(total.error());
  f.total_force = *total;
  for (std::int32_t i : f.indices)
    if (i >= static_cast<std::int32_t>(m.positions.size()))
      return fail(
          c, fmt::format("attribute indices: node {} out of range (the model has {} nodes)", i, m.positions.size()),
          ErrorCode::kInvalidArgument);
  return f;
}

}  // namespace hof::scene::detail
