// The attribute tables of the project file's <haptics> and <graphics> (detail/project_fields.h):
// per attribute its name, its reading and check, and its written text.

#include "hof/scene/detail/project_fields.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <initializer_list>
#include <sstream>
#include <utility>

#include "hof/core/text.h"

namespace hof::scene::detail {

std::string xml_escape(std::string_view text) {
  std::string out;
  for (const char c : valid_utf8(text)) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string number_text(double v) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

namespace {

using Problem = std::optional<std::string>;  // an error message, or none

std::string vec_text(const Vec3& v) { return number_text(v.x()) + " " + number_text(v.y()) + " " + number_text(v.z()); }

bool parse_number(std::string_view s, double& v) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(v);
}

// A number; `check` (the value, the element) refuses one out of range.
template <class T, class Get, class Check>
Field<T> number(std::string_view name, Get get, Check check) {
  return {name,
          [name, get, check](T& into, std::string_view element, std::string_view text) -> Problem {
            double v = 0.0;
            if (!parse_number(text, v)) return fmt::format("<{}> {}=\"{}\" is not a number", element, name, text);
            if (Problem e = check(v, element)) return e;
            get(into) = v;
            return std::nullopt;
          },
          [get](const T& from) { return number_text(get(from)); },
          [name, get, check](const T& from, std::string_view element) -> Problem {
            const double v = get(from);
            if (!std::isfinite(v)) return fmt::format("<{}> {}=\"{}\" is not a number", element, name, number_text(v));
            return check(v, element);
          }};
}
template <class T, class Get>
Field<T> number(std::string_view name, Get get) {
  return number<T>(name, get, [](double, std::string_view) -> Problem { return std::nullopt; });
}

// A value in [0, 1] (colours' parts, intensities, shininess).
template <class T, class Get>
Field<T> unit_number(std::string_view name, Get get) {
  return number<T>(name, get, [name](double v, std::string_view element) -> Problem {
    if (v >= 0.0 && v <= 1.0) return std::nullopt;
    return fmt::format("<{}> {} must be in [0, 1], got {}", element, name, v);
  });
}

// A whole number in [lo, hi] (checked before any conversion to int: casting an out-of-range
// double is undefined behaviour).
template <class T, class Get>
Field<T> count(std::string_view name, Get get, int lo, int hi) {
  return {name,
          [name, get, lo, hi](T& into, std::string_view element, std::string_view text) -> Problem {
            double v = 0.0;
            if (!parse_number(text, v)) return fmt::format("<{}> {}=\"{}\" is not a number", element, name, text);
            if (!(v >= lo && v <= hi && v == std::floor(v))) {
              return fmt::format("<{}> {}=\"{}\" must be a whole number from {} to {}", element, name, text, lo, hi);
            }
            get(into) = static_cast<int>(v);
            return std::nullopt;
          },
          [get](const T& from) { return fmt::format("{}", get(from)); },
          [name, get, lo, hi](const T& from, std::string_view element) -> Problem {
            if (get(from) >= lo && get(from) <= hi) return std::nullopt;
            return fmt::format("<{}> {}=\"{}\" must be a whole number from {} to {}", element, name, get(from), lo, hi);
          }};
}

template <class T, class Get>
Field<T> boolean(std::string_view name, Get get) {
  return {name,
          [name, get](T& into, std::string_view element, std::string_view text) -> Problem {
            if (text == "true" || text == "1")
              get(into) = true;
            else if (text == "false" || text == "0")
              get(into) = false;
            else
              return fmt::format("<{}> {}=\"{}\" must be true or false", element, name, text);
            return std::nullopt;
          },
          [get](const T& from) { return std::string(get(from) ? "true" : "false"); },
          [](const T&, std::string_view) -> Problem { return std::nullopt; }};
}

// Three numbers (more text after them is not read); `check` refuses a vector out of range.
template <class T, class Get, class Check>
Field<T> vector(std::string_view name, Get get, Check check) {
  return {name,
          [name, get, check](T& into, std::string_view element, std::string_view text) -> Problem {
            std::istringstream in{std::string(text)};
            Vec3 v;
            if (!(in >> v.x() >> v.y() >> v.z()) || !v.allFinite()) {
              return fmt::format("<{}> {}=\"{}\" must be three numbers", element, name, text);
            }
            if (Problem e = check(v, element)) return e;
            get(into) = v;
            return std::nullopt;
          },
          [get](const T& from) { return vec_text(get(from)); },
          [name, get, check](const T& from, std::string_view element) -> Problem {
            const Vec3& v = get(from);
            if (!v.allFinite()) return fmt::format("<{}> {}=\"{}\" must be three numbers", element, name, vec_text(v));
            return check(v, element);
          }};
}
template <class T, class Get>
Field<T> vector(std::string_view name, Get get) {
  return vector<T>(name, get, [](const Vec3&, std::string_view) -> Problem { return std::nullopt; });
}

// A colour: three numbers in [0, 1].
template <class T, class Get>
Field<T> colour(std::string_view name, Get get) {
  return vector<T>(name, get, [name](const Vec3& c, std::string_view element) -> Problem {
    if ((c.array() >= 0.0).all() && (c.array() <= 1.0).all()) return std::nullopt;
    return fmt::format("<{}> {} must be three numbers in [0, 1]", element, name);
  });
}

// Exactly N numbers (e.g. fungPre="a b d0 F0"); `meaning` says which, in the error.
template <class T, std::size_t N, class ToArray, class FromArray>
Field<T> numbers(std::string_view name, std::string_view meaning, ToArray to_array, FromArray from_array) {
  return {name,
          [name, meaning, from_array](T& into, std::string_view element, std::string_view text) -> Problem {
            const auto error = [&] {
              return fmt::format("<{}> {}=\"{}\" must be {} numbers ({})", element, name, text, N, meaning);
            };
            std::istringstream in{std::string(text)};
            std::array<double, N> v{};
            for (double& x : v) {
              if (!(in >> x) || !std::isfinite(x)) return error();
            }
            if (std::string rest; in >> rest) return error();
            from_array(into, v);
            return std::nullopt;
          },
          [to_array](const T& from) {
            std::string out;
            for (const double v : to_array(from)) out += (out.empty() ? "" : " ") + number_text(v);
            return out;
          },
          [name, meaning, to_array](const T& from, std::string_view element) -> Problem {
            for (const double v : to_array(from)) {
              if (!std::isfinite(v)) return fmt::format("<{}> {} must be {} numbers ({})", element, name, N, meaning);
            }
            return std::nullopt;
          }};
}

// One of named values; `unknown` is the error, with {} for the text.
template <class T, class E, class Get>
Field<T> choice(std::string_view name, Get get, std::vector<std::pair<std::string_view, E>> table,
                std::string_view unknown) {
  return {name,
          [get, table, unknown](T& into, std::string_view, std::string_view text) -> Problem {
            for (const auto& [n, value] : table) {
              if (n == text) {
                get(into) = value;
                return std::nullopt;
              }
            }
            return fmt::format(fmt::runtime(unknown), text);
          },
          [get, table](const T& from) {
            for (const auto& [n, value] : table) {
              if (value == get(from)) return std::string(n);
            }
            return std::string(table.front().first);
          },
          [](const T&, std::string_view) -> Problem { return std::nullopt; }};  // an enum: one of them
}

template <class T, class Get>
Field<T> string_field(std::string_view name, Get get) {
  return {name,
          [get](T& into, std::string_view, std::string_view text) -> Problem {
            get(into) = std::string(text);
            return std::nullopt;
          },
          [get](const T& from) { return std::string(get(from)); },
          [](const T&, std::string_view) -> Problem { return std::nullopt; }};
}

constexpr std::pair<std::string_view, RenderMode> kRenderModes[] = {{"shaded", RenderMode::kShaded},
                                                                    {"wireframe", RenderMode::kWireframe},
                                                                    {"shaded+wireframe", RenderMode::kShadedWireframe},
                                                                    {"points", RenderMode::kPoints}};
constexpr std::pair<std::string_view, ColorBy> kColorings[] = {{"material", ColorBy::kMaterial},
                                                               {"displacement", ColorBy::kDisplacement},
                                                               {"strain", ColorBy::kStrain},
                                                               {"stress", ColorBy::kStress}};

// Members reached by a generic lambda serve both the reading (T&) and the writing (const T&).
#define HOF_MEMBER(expr) \
  [](auto& t) -> auto& { return t.expr; }

}  // namespace

template <class T>
std::string write_fields(const Fields<T>& fields, const T& from) {
  std::string out;
  for (const Field<T>& f : fields)
    out += fmt::format("{}{}=\"{}\"", out.empty() ? "" : " ", f.name, xml_escape(f.write(from)));
  return out;
}

template std::string write_fields(const Fields<HofProject>&, const HofProject&);
template std::string write_fields(const Fields<haptics::SurfaceMaterial>&, const haptics::SurfaceMaterial&);
template std::string write_fields(const Fields<haptics::SafetyConfig>&, const haptics::SafetyConfig&);
template std::string write_fields(const Fields<procedures::NeedleConfig>&, const procedures::NeedleConfig&);
template std::string write_fields(const Fields<procedures::ShapedToolConfig>&, const procedures::ShapedToolConfig&);
template std::string write_fields(const Fields<procedures::TissueNeedleParameters>&,
                                  const procedures::TissueNeedleParameters&);
template std::string write_fields(const Fields<haptics::SpringEffect>&, const haptics::SpringEffect&);
template std::string write_fields(const Fields<haptics::ViscosityEffect>&, const haptics::ViscosityEffect&);
template std::string write_fields(const Fields<haptics::ConstantForceEffect>&, const haptics::ConstantForceEffect&);
template std::string write_fields(const Fields<GraphicsSetup>&, const GraphicsSetup&);
template std::string write_fields(const Fields<coupling::ContactSettings>&, const coupling::ContactSettings&);

const Fields<HofProject>& haptics_fields() {
  using P = HofProject;
  static const Fields<P> fields{
      string_field<P>("device", HOF_MEMBER(device)),
      number<P>("hapticRate", HOF_MEMBER(haptic_rate_hz)),
      choice<P, haptics::RendererKind>("renderer", HOF_MEMBER(renderer),
                                       {{"PenaltyRenderer", haptics::RendererKind::kPenalty},
                                        {"GodObjectRenderer", haptics::RendererKind::kGodObject},
                                        {"RuspiniRenderer", haptics::RendererKind::kRuspini}},
                                       "unknown renderer \"{}\" (RuspiniRenderer, GodObjectRenderer, PenaltyRenderer)"),
      number<P>("proxyRadius", HOF_MEMBER(proxy_radius_m)),
      boolean<P>("forceShading", HOF_MEMBER(force_shading)),
      choice<P, collision::TouchableFace>("touchableFace", HOF_MEMBER(touchable_face),
                                          {{"FRONT", collision::TouchableFace::kFront},
                                           {"BACK", collision::TouchableFace::kBack},
                                           {"FRONT_AND_BACK", collision::TouchableFace::kFrontAndBack}},
                                          "unknown touchableFace \"{}\" (FRONT, BACK, FRONT_AND_BACK)"),
      choice<P, coupling::ContactCoupling>(
          "coupling", HOF_MEMBER(coupling),
          {{"barycentric", coupling::ContactCoupling::kBarycentric},
           {"closest-vertex", coupling::ContactCoupling::kClosestVertex},
           {"compliance", coupling::ContactCoupling::kCompliance},
           {"fem-reaction", coupling::ContactCoupling::kFemReaction}},
          "unknown coupling \"{}\" (barycentric, closest-vertex, compliance, fem-reaction)"),
  };
  return fields;
}

const Fields<HofProject>& calibration_fields() {
  // 16 numbers read in turn (text after them is not read), as the reader always has.
  static const Fields<HofProject> fields{
      {"positionCalibration",
       [](HofProject& into, std::string_view, std::string_view text) -> Problem {
         std::istringstream values{std::string(text)};
         std::array<double, 16> m{};
         for (double& v : m) {
           if (!(values >> v)) return std::string("positionCalibration must be 16 numbers (a row-major 4x4 matrix)");
         }
         into.position_calibration = m;
         return std::nullopt;
       },
       [](const HofProject& from) {
         std::string out;
         for (std::size_t i = 0; i < 16; ++i) out += (i ? " " : "") + number_text(from.position_calibration[i]);
         return out;
       },
       [](const HofProject& from, std::string_view) -> Problem {
         for (const double v : from.position_calibration) {
           if (!std::isfinite(v)) return std::string("positionCalibration must be 16 numbers (a row-major 4x4 matrix)");
         }
         return std::nullopt;
       }},
  };
  return fields;
}

const Fields<haptics::SurfaceMaterial>& surface_fields() {
  using S = haptics::SurfaceMaterial;
  static const Fields<S> fields{
      choice<S, haptics::SurfaceKind>("type", HOF_MEMBER(kind),
                                      {{"SmoothSurface", haptics::SurfaceKind::kSmooth},
                                       {"FrictionalSurface", haptics::SurfaceKind::kFrictional},
                                       {"MagneticSurface", haptics::SurfaceKind::kMagnetic},
                                       {"ZeroForceSurface", haptics::SurfaceKind::kZeroForce}},
                                      "unknown surface type \"{}\""),
      number<S>("stiffness", HOF_MEMBER(stiffness)),
      number<S>("damping", HOF_MEMBER(damping_n_s_per_m)),
      boolean<S>("useRelativeValues", HOF_MEMBER(use_relative_values)),
      number<S>("staticFriction", HOF_MEMBER(static_friction)),
      number<S>("dynamicFriction", HOF_MEMBER(dynamic_friction)),
      number<S>("snapDistance", HOF_MEMBER(snap_distance_m)),
  };
  return fields;
}

const Fields<haptics::SafetyConfig>& safety_fields() {
  using S = haptics::SafetyConfig;
  static const Fields<S> fields{
      number<S>("fadeIn", HOF_MEMBER(fade_in_s)),
      number<S>("fadeOut", HOF_MEMBER(fade_out_s)),
      number<S>("maxSnapshotAge", HOF_MEMBER(max_snapshot_age_s)),
      count<S>("maxConsecutiveOverruns", HOF_MEMBER(max_consecutive_overruns), 1, 1000000),
      number<S>("maxForce", HOF_MEMBER(max_force_n),
                [](double v, std::string_view) -> Problem {
                  if (v >= 0.0) return std::nullopt;
                  return fmt::format("<safety> maxForce must be >= 0 N (0: the device's own limit), got {}", v);
                }),
  };
  return fields;
}

const Fields<HofProject>& options_fields() {
  using P = HofProject;
  static const Fields<P> fields{
      boolean<P>("useBoundTree", HOF_MEMBER(use_bound_tree)),
      count<P>("maxTrianglesInLeaf", HOF_MEMBER(max_triangles_in_leaf), 1, 1000000),
  };
  return fields;
}

const Fields<HofProject>& stylus_fields() {
  using P = HofProject;
  static const Fields<P> fields{
      number<P>("radius", HOF_MEMBER(stylus_radius_m)),
      number<P>("length", HOF_MEMBER(stylus_length_m)),
  };
  return fields;
}

const Fields<procedures::NeedleConfig>& needle_fields() {
  using N = procedures::NeedleConfig;
  static const Fields<N> fields{
      choice<N, procedures::NeedleAxis>("axis", HOF_MEMBER(axis),
                                        {{"motion", procedures::NeedleAxis::kMotion},
                                         {"normal", procedures::NeedleAxis::kNormal},
                                         {"stylus", procedures::NeedleAxis::kStylus}},
                                        "<needle> axis=\"{}\": expected motion, normal or stylus"),
      number<N>("velocityFilter", HOF_MEMBER(velocity_filter_s),
                [](double v, std::string_view) -> Problem {
                  if (v >= 0.0 && v <= 1.0) return std::nullopt;
                  return fmt::format("<needle> velocityFilter must be in [0, 1] s, got {}", v);
                }),
      number<N>("length", HOF_MEMBER(geometry.length_m)),
      number<N>("shaftDiameter", HOF_MEMBER(geometry.shaft_diameter_m)),
      number<N>("tipDiameter", HOF_MEMBER(geometry.tip_diameter_m)),
      number<N>("tipLength", HOF_MEMBER(geometry.tip_length_m)),
      number<N>("syringeDiameter", HOF_MEMBER(geometry.syringe_diameter_m)),
      number<N>("syringeLength", HOF_MEMBER(geometry.syringe_length_m)),
  };
  return fields;
}

const Fields<procedures::ShapedToolConfig>& tool_fields() {
  using S = procedures::ShapedToolConfig;
  static const Fields<S> fields{
      choice<S, procedures::ToolShape>("shape", HOF_MEMBER(shape),
                                       {{"sphere", procedures::ToolShape::kSphere},
                                        {"capsule", procedures::ToolShape::kCapsule},
                                        {"mesh", procedures::ToolShape::kMesh}},
                                       "<tool> shape=\"{}\": expected sphere, capsule or mesh"),
      number<S>("radius", HOF_MEMBER(radius_m)),
      number<S>("length", HOF_MEMBER(length_m)),
      string_field<S>("mesh", HOF_MEMBER(mesh)),
      numbers<S, 4>(
          "orientation", "axis x y z, angle rad", [](const S& t) { return t.orientation; },
          [](S& t, const std::array<double, 4>& v) { t.orientation = v; }),
      number<S>("stiffness", HOF_MEMBER(stiffness_n_per_m)),
      number<S>("damping", HOF_MEMBER(damping_n_s_per_m)),
      string_field<S>("device", HOF_MEMBER(device)),
  };
  return fields;
}

std::optional<std::string> check_tool(const procedures::ShapedToolConfig& tool) {
  if (auto ok = procedures::validate(tool); !ok) return ok.error().message;
  return std::nullopt;
}

const Fields<procedures::TissueNeedleParameters>& tissue_fields() {
  using T = procedures::TissueNeedleParameters;
  using Fung = std::array<double, 4>;
  const auto fung = [](std::string_view name, procedures::FungParameters T::*member) {
    return numbers<T, 4>(
        name, "a 1/m, b N, d0 m, F0 N",
        [member](const T& t) {
          const auto& f = t.*member;
          return Fung{f.a_per_m, f.b_n, f.d0_m, f.f0_n};
        },
        [member](T& t, const Fung& v) {
          t.*member = {v[0], v[1], v[2], v[3]};
        });
  };
  static const Fields<T> fields{
      boolean<T>("pierceable", HOF_MEMBER(pierceable)),
      choice<T, procedures::NeedleForceModel>("model", HOF_MEMBER(model),
                                              {{"fung", procedures::NeedleForceModel::kFung},
                                               {"simone-okamura", procedures::NeedleForceModel::kSimoneOkamura}},
                                              "<tissue> model=\"{}\": expected fung or simone-okamura"),
      number<T>("capsule", HOF_MEMBER(capsule_m)),
      number<T>("punctureForce", HOF_MEMBER(puncture_force_n)),
      number<T>("relaxationTime", HOF_MEMBER(relaxation_time_s)),
      choice<T, procedures::FungForm>(
          "fungForm", HOF_MEMBER(fung_form),
          {{"integrated", procedures::FungForm::kIntegrated}, {"printed", procedures::FungForm::kPrinted}},
          "<tissue> fungForm=\"{}\": expected integrated ((F0 + b) e^(a (d - d0)) - b) or printed (... + b)"),
      fung("fungPre", &T::fung_pre),
      fung("fungPost", &T::fung_post),
      numbers<T, 3>(
          "stiffness", "a0 N, a1 N/m, a2 N/m2",
          [](const T& t) {
            return std::array<double, 3>{t.stiffness.a0_n, t.stiffness.a1_n_per_m, t.stiffness.a2_n_per_m2};
          },
          [](T& t, const std::array<double, 3>& v) {
            t.stiffness = {v[0], v[1], v[2]};
          }),
      number<T>("cuttingForce", HOF_MEMBER(cutting_force_n)),
      numbers<T, 4>(
          "friction", "Cp N/m, Cn N/m, bp N s/m2, bn N s/m2",
          [](const T& t) {
            const procedures::KarnoppFriction& f = t.friction;
            return Fung{f.static_positive_n_per_m, f.static_negative_n_per_m, f.damping_positive_n_s_per_m2,
                        f.damping_negative_n_s_per_m2};
          },
          [](T& t, const Fung& v) {
            t.friction.static_positive_n_per_m = v[0];
            t.friction.static_negative_n_per_m = v[1];
            t.friction.damping_positive_n_s_per_m2 = v[2];
            t.friction.damping_negative_n_s_per_m2 = v[3];
          }),
      number<T>("frictionVelocityBand", HOF_MEMBER(friction.velocity_band_m_per_s)),
      number<T>("lateralStiffness", HOF_MEMBER(lateral_stiffness_n_per_m)),
      number<T>("lateralDamping", HOF_MEMBER(lateral_damping_n_s_per_m)),
      number<T>("spreadRadius", HOF_MEMBER(spread_radius_m)),
      number<T>("pathTolerance", HOF_MEMBER(path_tolerance_m)),
  };
  return fields;
}

const Fields<haptics::SpringEffect>& spring_effect_fields() {
  using S = haptics::SpringEffect;
  static const Fields<S> fields{
      vector<S>("position", HOF_MEMBER(position_m)),
      number<S>("springConstant", HOF_MEMBER(spring_constant_n_per_m)),
      number<S>("startDistance", HOF_MEMBER(start_distance_m)),
      number<S>("escapeDistance", HOF_MEMBER(escape_distance_m)),
      number<S>("damping", HOF_MEMBER(damping_n_s_per_m)),
  };
  return fields;
}

const Fields<haptics::ViscosityEffect>& viscosity_effect_fields() {
  using V = haptics::ViscosityEffect;
  static const Fields<V> fields{
      number<V>("viscosity", HOF_MEMBER(viscosity_pa_s)),
      number<V>("radius", HOF_MEMBER(radius_m)),
      number<V>("dampingFactor", HOF_MEMBER(damping_factor)),
      boolean<V>("enabled", HOF_MEMBER(enabled)),
  };
  return fields;
}

const Fields<haptics::ConstantForceEffect>& force_field_fields() {
  static const Fields<haptics::ConstantForceEffect> fields{
      vector<haptics::ConstantForceEffect>("force", HOF_MEMBER(force_n))};
  return fields;
}

const Fields<GraphicsSetup>& graphics_fields() {
  using G = GraphicsSetup;
  static const Fields<G> fields{
      vector<G>("viewpoint", HOF_MEMBER(viewpoint_m)),
      vector<G>("lookAt", HOF_MEMBER(look_at_m)),
      choice<G, RenderMode>("renderMode", HOF_MEMBER(render_mode), {std::begin(kRenderModes), std::end(kRenderModes)},
                            "unknown renderMode \"{}\" (shaded, wireframe, shaded+wireframe, points)"),
      choice<G, ColorBy>("colorBy", HOF_MEMBER(color_by), {std::begin(kColorings), std::end(kColorings)},
                         "unknown colorBy \"{}\" (material, displacement, strain, stress)"),
  };
  return fields;
}

const Fields<GraphicsSetup>& material_fields() {
  using G = GraphicsSetup;
  static const Fields<G> fields{
      colour<G>("diffuseColor", HOF_MEMBER(diffuse_color)),
      colour<G>("specularColor", HOF_MEMBER(specular_color)),
      unit_number<G>("shininess", HOF_MEMBER(shininess)),
      unit_number<G>("transparency", HOF_MEMBER(transparency)),
  };
  return fields;
}

const Fields<GraphicsSetup>& light_fields() {
  using G = GraphicsSetup;
  static const Fields<G> fields{
      boolean<G>("headlight", HOF_MEMBER(headlight)),
      unit_number<G>("headlightIntensity", HOF_MEMBER(headlight_intensity)),
      vector<G>("direction", HOF_MEMBER(light_direction),
                [](const Vec3& d, std::string_view) -> Problem {
                  if (d.norm() > 0.0) return std::nullopt;
                  return std::string("<light> direction must not be zero");
                }),
      unit_number<G>("intensity", HOF_MEMBER(light_intensity)),
      unit_number<G>("ambientIntensity", HOF_MEMBER(ambient_intensity)),
  };
  return fields;
}

const Fields<coupling::ContactSettings>& contact_fields() {
  using C = coupling::ContactSettings;
  const auto non_negative = [](std::string_view name, std::string_view unit) {
    return [name, unit](double v, std::string_view element) -> Problem {
      if (v >= 0.0) return std::nullopt;
      return fmt::format("<{}> {} must be ≥ 0{}, got {}", element, name, unit, v);
    };
  };
  static const Fields<C> fields{
      boolean<C>("enabled", HOF_MEMBER(enabled)),
      choice<C, coupling::ContactResponse>("response", HOF_MEMBER(response),
                                           {{"penalty", coupling::ContactResponse::kPenalty},
                                            {"friction", coupling::ContactResponse::kFrictionConstraint}},
                                           "<contact> response=\"{}\": expected penalty (SOFA's "
                                           "PenalityContactForceField) or friction (FrictionContactConstraint)"),
      number<C>("stiffness", HOF_MEMBER(stiffness_n_per_m), non_negative("stiffness", " N/m")),
      number<C>("friction", HOF_MEMBER(friction), non_negative("friction", "")),
      number<C>("alarmDistance", HOF_MEMBER(alarm_distance_m), non_negative("alarmDistance", " m")),
      number<C>("contactDistance", HOF_MEMBER(contact_distance_m), non_negative("contactDistance", " m")),
      boolean<C>("selfCollision", HOF_MEMBER(self_collision)),
  };
  return fields;
}

#undef HOF_MEMBER

}  // namespace hof::scene::detail

namespace hof::scene {

std::string_view render_mode_name(RenderMode mode) {
  for (const auto& [name, value] : detail::kRenderModes) {
    if (value == mode) return name;
  }
  return detail::kRenderModes[0].first;
}

std::string_view color_by_name(ColorBy colouring) {
  for (const auto& [name, value] : detail::kColorings) {
    if (value == colouring) return name;
  }
  return detail::kColorings[0].first;
}

}  // namespace hof::scene

namespace hof::scene::detail {

std::optional<std::string> check_surface(const haptics::SurfaceMaterial& surface) {
  if (auto valid = haptics::validate(surface); !valid) return valid.error().message;
  return std::nullopt;
}

std::optional<std::string> check_tissue(const procedures::TissueNeedleParameters& tissue, std::string_view body) {
  const std::string what = body.empty() ? std::string("<tissue>") : fmt::format("<tissue body=\"{}\">", body);
  if (auto ok = procedures::validate(tissue, what); !ok) return ok.error().message;
  return std::nullopt;
}

std::optional<std::string> check_needle(const procedures::NeedleConfig& needle) {
  if (auto ok = procedures::validate(needle); !ok) return ok.error().message;
  return std::nullopt;
}

std::optional<std::string> check_contact(const coupling::ContactSettings& contact) {
  if (contact.contact_distance_m <= contact.alarm_distance_m) return std::nullopt;
  return fmt::format(
      "<contact> contactDistance {} is larger than alarmDistance {} (pairs are detected within the "
      "alarm distance: the contact distance must not exceed it)",
      contact.contact_distance_m, contact.alarm_distance_m);
}

std::optional<std::string> check_haptic_rate(const HofProject& project) {
  if (project.haptic_rate_hz >= 100.0 && project.haptic_rate_hz <= 20000.0) return std::nullopt;
  return fmt::format("hapticRate must be in [100, 20000] Hz, got {}", project.haptic_rate_hz);
}

}  // namespace hof::scene::detail
