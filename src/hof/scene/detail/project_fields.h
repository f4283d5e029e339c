#pragma once
/// @file
/// The attributes of the project file's <haptics> and <graphics> elements, one table per
/// element: each attribute's name, how its text is read and checked, and how it is written.
/// The reader (project.cpp), the writer (project_write.cpp) and the typed edit
/// (project_edit.cpp) all go through these tables, so a name, a check or a number format is
/// stated once.

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hof/scene/project.h"

namespace hof::scene::detail {

/// One attribute of an element whose values live in a `T`.
template <class T>
struct Field {
  std::string_view name;
  /// Reads the attribute's text into `into`, checked as the file reader checks it. The error
  /// message names the element (`element`, e.g. "surface") and the attribute as a file's
  /// reader reports them; `into` may be half-changed on error (callers work on a copy).
  std::function<std::optional<std::string>(T& into, std::string_view element, std::string_view text)> read;
  /// The attribute's value as the writer writes it (shortest round-trip numbers).
  std::function<std::string(const T& from)> write;
  /// Checks the value `from` holds as `read` checks one it reads (a typed edit made in memory,
  /// not read from text, goes through it); the error as `read` words it.
  std::function<std::optional<std::string>(const T& from, std::string_view element)> check;
};

template <class T>
using Fields = std::vector<Field<T>>;

/// Reads every attribute of `fields` that `attribute(name)` finds (nullopt: absent, the value
/// left as it is) into `into`; the first error, if any.
template <class T, class Lookup>
std::optional<std::string> read_fields(const Fields<T>& fields, std::string_view element, Lookup&& attribute, T& into) {
  std::optional<std::string> first;
  for (const Field<T>& f : fields) {
    const std::optional<std::string_view> text = attribute(f.name);
    if (!text) continue;
    if (auto error = f.read(into, element, *text); error && !first) first = std::move(error);
  }
  return first;
}

/// The first of `fields`' checks that `value` fails.
template <class T>
std::optional<std::string> check_fields(const Fields<T>& fields, std::string_view element, const T& value) {
  for (const Field<T>& f : fields) {
    if (auto problem = f.check(value, element)) return problem;
  }
  return std::nullopt;
}

/// `name="value"` of every field, separated by spaces, values escaped for XML.
template <class T>
std::string write_fields(const Fields<T>& fields, const T& from);

/// Text for an XML attribute value: markup characters escaped; bytes that are not UTF-8 (a
/// Latin-1 name, say) written as U+FFFD so the file stays well-formed.
[[nodiscard]] std::string xml_escape(std::string_view text);
/// The shortest text that reads back as `v`.
[[nodiscard]] std::string number_text(double v);

// ---- the tables, in the order the writer writes the attributes
/// <haptics>: device, hapticRate, renderer, proxyRadius, forceShading, touchableFace, coupling.
[[nodiscard]] const Fields<HofProject>& haptics_fields();
/// <calibration>: positionCalibration.
[[nodiscard]] const Fields<HofProject>& calibration_fields();
/// <surface> (in <haptics>, <body>, <obstacle>).
[[nodiscard]] const Fields<haptics::SurfaceMaterial>& surface_fields();
[[nodiscard]] const Fields<haptics::SafetyConfig>& safety_fields();
/// <options>: useBoundTree, maxTrianglesInLeaf.
[[nodiscard]] const Fields<HofProject>& options_fields();
/// <stylus>: radius, length.
[[nodiscard]] const Fields<HofProject>& stylus_fields();
[[nodiscard]] const Fields<procedures::NeedleConfig>& needle_fields();
/// <tool>: shape, radius, length, mesh, orientation, stiffness, damping, device.
[[nodiscard]] const Fields<procedures::ShapedToolConfig>& tool_fields();
/// procedures::validate of a shaped tool.
[[nodiscard]] std::optional<std::string> check_tool(const procedures::ShapedToolConfig& tool);
/// <tissue> (its body="" attribute aside: it names which body the set is for).
[[nodiscard]] const Fields<procedures::TissueNeedleParameters>& tissue_fields();
[[nodiscard]] const Fields<haptics::SpringEffect>& spring_effect_fields();
[[nodiscard]] const Fields<haptics::ViscosityEffect>& viscosity_effect_fields();
[[nodiscard]] const Fields<haptics::ConstantForceEffect>& force_field_fields();
/// <graphics>: viewpoint, lookAt, renderMode, colorBy.
[[nodiscard]] const Fields<GraphicsSetup>& graphics_fields();
/// <material> in <graphics>.
[[nodiscard]] const Fields<GraphicsSetup>& material_fields();
/// <light> in <graphics>.
[[nodiscard]] const Fields<GraphicsSetup>& light_fields();
/// <contact>: enabled, response, stiffness, friction, alarmDistance, contactDistance,
/// selfCollision.
[[nodiscard]] const Fields<coupling::ContactSettings>& contact_fields();

// ---- the checks of a whole element, after its attributes (reader and edit alike)
/// haptics::validate of a surface.
[[nodiscard]] std::optional<std::string> check_surface(const haptics::SurfaceMaterial& surface);
/// procedures::validate of a tissue set; `body` empty: the set for every body.
[[nodiscard]] std::optional<std::string> check_tissue(const procedures::TissueNeedleParameters& tissue,
                                                      std::string_view body);
/// procedures::validate of a needle.
[[nodiscard]] std::optional<std::string> check_needle(const procedures::NeedleConfig& needle);
/// contactDistance ≤ alarmDistance.
[[nodiscard]] std::optional<std::string> check_contact(const coupling::ContactSettings& contact);
/// The haptic rate in [100, 20000] Hz (checked once the whole file is read).
[[nodiscard]] std::optional<std::string> check_haptic_rate(const HofProject& project);

}  // namespace hof::scene::detail
