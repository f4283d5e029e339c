#pragma once
/// @file
/// The bench's model recipes: the four standard livers and a hexahedral sparse grid over the
/// medium one, and the mechanics settings of each cell (the thesis' and the physiological
/// ones, the solvers, the haptic-rate CG). Every timer builds its model from these, so a cell
/// means the same model wherever it is timed. Each model is a SOFA scene (body_scene) read by
/// the builder's reader, as `hof run` reads a user's scene, and its body is made by
/// scene::deformable_body: the bench times the models `hof run` would simulate.

#include <array>
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "hof/core/error.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/scripted_device.h"
#include "hof/mechanics/mechanical_model.h"
#include "hof/mesh/boundary.h"
#include "hof/mesh/liver_generator.h"

namespace hof::app::bench {

/// A body of the bench: its volume mesh (tetrahedra or hexahedra) and its surface.
struct Body {
  std::string name;
  std::vector<Vec3> nodes;
  std::vector<mesh::Tet> tets;
  std::vector<mesh::Hex> hexes;
  std::size_t surface_triangles{0};
  mesh::TriMesh surface;
  /// The sparse grid's: the closed surface it fills (the medium liver's).
  std::optional<mesh::TriMesh> filled_surface;
};

/// The sparse grid's nodes per axis: cells of about 1 cm over the medium liver.
inline constexpr std::array<int, 3> kSparseGridNodes{24, 16, 10};

/// The bodies, each generated once on first use (the fine liver takes seconds).
class Bodies {
 public:
  /// `simple`, `coarse`, `medium`, `fine` (mesh::LiverResolution) or `sparse-grid`.
  [[nodiscard]] Expected<const Body*> by_name(const std::string& name);

 private:
  Expected<const Body*> liver(mesh::LiverResolution r);
  Expected<const Body*> sparse_grid();
  std::map<std::string, Body> bodies_;
};

enum class Field { kSprings, kSmall, kLarge, kNeoHookean, kHexahedra };
enum class Settings { kThesis, kPhysiological };
enum class Solver { kExplicitEuler, kSymplecticEuler, kRungeKutta4, kStatic, kImplicitCg, kImplicitLdlt };

[[nodiscard]] const char* field_name(Field f);
[[nodiscard]] const char* settings_name(Settings s);
[[nodiscard]] const char* solver_name(Solver s);
[[nodiscard]] std::string dt_label(double dt);

/// The implicit Euler + CG a recipe's scene states; the defaults are the bench's own (CG 25
/// with no early stop at dt 0.02 s, Rayleigh 0.1 and 0.1, gravity on).
struct ImplicitCgScene {
  double dt_s{0.02};
  int iterations{25};
  double tolerance{1e-12};  ///< CG's tolerance and threshold
  double rayleigh_mass{0.1};
  bool gravity{true};
};

/// The body with a force field and settings, implicit Euler + CG, resting on its lowest 4 mm,
/// as a SOFA scene (the mesh inline; the springs with HoF's rule, a HoF extension of
/// MeshSpringForceField).
[[nodiscard]] std::string body_scene(const Body& b, Field field, Settings s, const ImplicitCgScene& solver = {});
/// body_scene() read by the builder's SOFA reader (scene::read_sofa_scene_text), as `hof run`
/// reads a scene, with what a scene cannot say set after (see the definition).
[[nodiscard]] mechanics::ModelConfig body_config(const Body& b, Field field, Settings s,
                                                 const ImplicitCgScene& solver = {});
/// Switches the ODE (and linear) solver of `c` and sets its step.
void set_solver(mechanics::ModelConfig& c, Solver s, double dt_s);

/// The haptic-rate cells' name: warm-started two-level CG (use_haptic_rate_solver).
inline constexpr const char* kHapticRateCell = "two-level-warm";

/// The haptic-rate CG: few warm-started iterations, the matrix assembled every few steps.
void use_haptic_rate_cg(mechanics::ModelConfig& c);

/// The physiological co-rotational liver with implicit Euler + CG at dt: most of the matrix
/// past the thesis' own figures. Gravity off where the organ is pressed (carried by the tissue
/// around it, as in the example scenes).
struct CorotationalSetup {
  double dt_s;
  int iterations{25};
  bool haptic_rate_cg{false};
  bool gravity{true};
};

[[nodiscard]] mechanics::ModelConfig corotational_config(const Body& b, const CorotationalSetup& s);

/// The co-rotational liver of the coupling cells: no gravity, strongly damped (quasi-static
/// press), CG 100 to 1e-9.
[[nodiscard]] mechanics::ModelConfig coupling_press_config(const Body& b);

/// The surface vertex every press comes down on: the highest near the middle of the top.
[[nodiscard]] std::size_t pressed_vertex(const Body& b, const mesh::BoundarySurface& boundary);

/// The press of the framework cells: from 1 cm above the point, 8 mm deep at 2 cm/s, held.
[[nodiscard]] haptics::MotionConfig framework_press(const Vec3& top);

/// The session of the framework cells: 1 kHz Ruspini renderer, the given coupling.
[[nodiscard]] coupling::SessionConfig framework_session_config(coupling::ContactCoupling mode);

}  // namespace hof::app::bench
