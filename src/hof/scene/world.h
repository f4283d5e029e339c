#pragma once
/// @file
/// The one builder: any input — a `.hof` project, a SOFA `.scn`, an X3D scene — becomes a
/// World: its bodies (deformable and rigid), their touchable surfaces and materials, the
/// force effects, the device and its calibration, the renderer and the viewpoint. `hof run`,
/// `hof bench`, `hof check` (and the window) only call build_world(); no command invents a
/// physical parameter. Every value comes from the file or from a documented default, listed
/// in World::defaults (which `hof check` prints) and overridable by a `.hof` project.
///
/// Bodies:
///  - deformable: every SOFA node with an ODE solver (a child without one is solved by its
///    parent's, as in SOFA); an X3D DeformableShape (mesh springs on its triangles, the
///    defaults below); the bodies of a `.hof` project's scene;
///  - rigid and fixed: an X3D Shape with a haptic surface (never deformed);
///  - a world of force effects only (no shape) runs too.
///
/// A bare scene (`.scn`, `.x3d`, or a project whose device is `auto`) gets the default probe:
/// the device workspace fitted to the world's bounds (as H3D's FitToBoxTransform) and a
/// scripted poke that starts outside the first deformable body (else the first rigid one)
/// and presses it along its outward normal, whatever the scene's up axis.

#include <array>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/session.h"
#include "hof/scene/project.h"
#include "hof/scene/project_edit.h"

namespace hof::scene {

/// Defaults for an X3D DeformableShape, which carries no mechanics of its own (documented in
/// docs/project-format.md; a `.hof` project's <set> elements override them by name).
/// An open sheet is a drum skin: springs pre-tensioned (rest lengths 0.9 of the drawn ones)
/// with the border held, so that it resists a press across its plane from the start
/// (untensioned springs in a plane have no stiffness across it: the sheet would fly off the
/// proxy). A closed surface is held by its lowest tenth, untensioned.
struct X3dDeformableDefaults {
  double spring_stiffness_n_per_m{2000.0};
  double spring_damping_n_s_per_m{1.0};
  double open_sheet_rest_length_scale{0.9};
  double total_mass_kg{0.1};
  double rayleigh{0.1};
  double dt_s{0.01};
};

/// How a shape looks (an X3D Material).
struct Appearance {
  Vec3 diffuse_color{0.8, 0.8, 0.8};
  double transparency{0.0};
};

/// A shape that is only seen: no haptic surface (an X3D Shape without one), never touched.
struct VisualShape {
  std::string name;
  mesh::TriMesh mesh;  ///< world frame, m
  Appearance appearance;
};

struct World {
  std::string name;
  std::filesystem::path file;        ///< what the user gave
  std::filesystem::path scene_path;  ///< the scene it points to (resolved), or the file itself
  HofProject project;                ///< every setting (read from the project, or defaults)
  std::vector<coupling::SessionBody> bodies;
  coupling::SessionConfig config;
  std::string device;         ///< the device spec (the default probe resolved)
  bool default_probe{false};  ///< the device is the builder's probe
  /// The default probe: seconds until it reaches the surface, and its whole press (0 when it
  /// does not press a body).
  double probe_arrival_s{0.0};
  double probe_press_s{0.0};
  std::string length_unit{"m"};      ///< "m", or "scene units" for a SOFA scene (no unit)
  std::vector<std::string> skipped;  ///< components not simulated, "TYPE 'name' (line N)"
  std::vector<std::string> ignored;  ///< components needing no counterpart (plugins, display, default loops)
  std::map<std::string, Appearance> appearances;  ///< by body name, where the file gives one
  std::vector<VisualShape> visuals;               ///< shapes only seen
  /// Why nothing in the world can be touched (no touchable body, no force effect), in a
  /// sentence; "" when something can. Such a world opens (it is shown) but `hof run` has
  /// nothing to render and exits with its own status.
  std::string nothing_to_touch;
  std::vector<std::string> warnings;
  std::vector<std::string> defaults;  ///< "what = value (why)" for every default the builder used
  /// The calibration the file gave (identity when none), before the default probe fitted one.
  std::array<double, 16> file_calibration{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

/// Builds the world of `file`. `device_override` (the --device option) replaces the file's
/// device. Errors start with the file (the project, then the scene with its resolved path).
[[nodiscard]] Expected<World> build_world(const std::filesystem::path& file, const std::string& device_override = {});
/// The world of a project held in memory (the window's, edited since it was read); `file` is
/// where it lives (its scene and meshes are relative to it).
[[nodiscard]] Expected<World> build_world(const HofProject& project, const std::filesystem::path& file,
                                          const std::string& device_override = {});

/// A tool with a shape from a command-line spec (`hof run --tool`, Python's World.load):
/// "SHAPE[,ATTRIBUTE=VALUE...]" with the attributes of the project's <tool> element, e.g.
/// "capsule,radius=0.004,length=0.05", "sphere,radius=0.006", "mesh,mesh=tool.stl". Errors
/// name the spec and the attribute.
[[nodiscard]] Expected<procedures::ShapedToolConfig> parse_tool_spec(std::string_view spec);
/// Mounts `tool` on the world's stylus in place of any needle or earlier tool (world.config's
/// tool and tool coupling; project.tool). A mesh file is relative to the world's file.
[[nodiscard]] Expected<void> mount_tool(World& w, const procedures::ShapedToolConfig& tool);

/// A model as a deformable body, made as the builder makes every body of a world: the
/// boundary of its volume elements (a hexahedral grid's, or itself for a surface model) as
/// its touchable surface, mapped to its nodes. For those who hold a model configuration
/// without a file (`hof bench`'s cells), so that their bodies are the ones `hof run` makes.
[[nodiscard]] Expected<coupling::SessionBody> deformable_body(const mechanics::ModelConfig& config);

/// Writes what a session changed through its command seam into `project` (parameters as
/// <set> elements, replacing an earlier value of the same parameter; surfaces in <bodies>),
/// so that the next save holds them.
void record_changes(HofProject& project, const coupling::Session& session);
/// The parameter part of record_changes(): each change as a <set>, replacing an earlier value.
void record_parameters(HofProject& project, const std::vector<ParameterChange>& changes);

/// The commands that carry a project edit (`next` is the project with `edit` made) to a
/// running session of the world's `bodies` (their names, in the session's order: BodyId i is
/// bodies[i]): the surface material of every body without one
/// of its own, the renderer, the force effects, the calibration, the force limit. An empty
/// list: the change needs no command (the graphics and the stylus, drawn by the window).
/// nullopt: it cannot be made live (it takes effect when the project is read again). The
/// device and the needle are the caller's (they hold handles on them).
[[nodiscard]] std::optional<std::vector<coupling::Command>> live_commands(const HofProject& next,
                                                                          const ProjectEdit& edit,
                                                                          const std::vector<std::string>& bodies);

/// Gives the tetrahedra of `config` whose centroid lies in `region` the region's Young's
/// modulus (in its force field, or every tetrahedral one); returns how many. Errors: no such
/// force field, a modulus that is not positive.
[[nodiscard]] Expected<std::size_t> apply_material_region(mechanics::ModelConfig& config, const MaterialRegion& region);

/// The spec of the default probe for `bodies` under `calibration` (a scripted poke in the
/// device frame), and a calibration that fits the device workspace to the bodies' bounds.
struct DefaultProbe {
  std::string device;
  double arrival_s{0.0};  ///< until the probe reaches the surface (0: it presses nothing)
  double press_s{0.0};    ///< the whole press: approach, press, hold, retract
  std::array<double, 16> calibration{};
  std::string description;
};
/// `calibration`: the file's (kept), or null to fit one.
[[nodiscard]] DefaultProbe default_probe(const std::vector<coupling::SessionBody>& bodies, double workspace_radius_m,
                                         double device_stiffness_n_per_m, double max_force_n,
                                         const std::array<double, 16>* calibration = nullptr,
                                         double device_max_stiffness_n_per_m = 3000.0,
                                         const Vec3& effects_centre = Vec3::Zero(), double proxy_radius = 0.0);
/// Where the default probe circles in a world of force effects only: where the first effect
/// that acts at one place is (a spring's anchor; 5 mm above a magnet's highest vertex);
/// the origin when every effect acts everywhere (viscosity, constant and function effects).
[[nodiscard]] Vec3 default_probe_effects_centre(const haptics::ForceEffects& effects);

}  // namespace hof::scene
