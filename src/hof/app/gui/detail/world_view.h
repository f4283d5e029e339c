#pragma once
/// @file
/// What the window's panels read: the world on screen as the window keeps it (its bodies,
/// their parameters, the project's settings, the latest telemetry), as a read-only view. The
/// panels never change it; they return commands (gui_command.h) that the window applies.

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hof/coupling/session.h"
#include "hof/haptics/device_backends/replay_device.h"
#include "hof/haptics/surface_snapshot.h"
#include "hof/mechanics/von_mises_stress.h"
#include "hof/procedures/needle.h"
#include "hof/procedures/shaped_tool.h"
#include "hof/render/camera.h"
#include "hof/render/gl_renderer.h"
#include "hof/scene/model_parameters.h"
#include "hof/scene/project.h"

namespace hof::app::gui {

using Clock = std::chrono::steady_clock;
constexpr float kPanelWidth = 390.0f;
constexpr double kPlotSeconds = 5.0;
constexpr double kPlotRateHz = 100.0;
constexpr std::size_t kPlotPoints = static_cast<std::size_t>(kPlotSeconds * kPlotRateHz);

inline double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

/// A snapshot layer as the window draws it.
struct LayerView {
  render::MeshBuffer mesh;
  std::vector<haptics::SurfacePart> parts;
  std::vector<Vec3> rest;
  std::vector<render::Rgba> colours;
  const haptics::SurfaceSnapshot* latest{nullptr};  // valid until the next acquire (this thread)
  double max_displacement_m{0.0};
  double max_strain{0.0};
  std::vector<double> strain;  // per vertex (colorBy strain)
  std::vector<double> stress;  // per vertex, Pa (colorBy stress; from the bodies' node stress)
  double max_stress_pa{0.0};
  std::vector<double> ranked;  // scratch for its percentile
};

/// A shape only seen (no haptic surface).
struct VisualView {
  render::MeshBuffer mesh;
  render::Material material;
};

struct BodyView {
  std::string name;
  std::optional<render::Material> material;  // the file's (an X3D Material), else the project's
  bool deformable{false};
  int layer{0};
  bool collides{false};    // it takes part in contact between bodies (its collision models)
  std::int32_t group{-1};  // its collision group (SOFA `group`; bodies of one group never touch)
  /// The model as it was last built (the world opened, or a structural edit): its mesh and
  /// components. Not its current values: those are the session's (Session::parameter()); the
  /// window never keeps a second copy of them.
  std::shared_ptr<const mechanics::ModelConfig> structure;
  std::vector<std::string> parameters;  // "component/parameter"
  std::vector<Vec3> fixed_points;
  std::shared_ptr<mechanics::VonMisesStress> stress;  // made on first use (colorBy stress)
  std::vector<double> node_stress;                    // Pa, scratch

  /// What the panels show of a model just built.
  void set_structure(const mechanics::ModelConfig& c) {
    structure = std::make_shared<const mechanics::ModelConfig>(c);
    parameters = scene::parameter_names(c);
    fixed_points.clear();
    for (const auto& f : c.fixed) {
      for (const std::int32_t i : f.indices) {
        if (i >= 0 && static_cast<std::size_t>(i) < c.positions.size())
          fixed_points.push_back(c.positions[static_cast<std::size_t>(i)]);
      }
    }
    stress.reset();
  }
};

/// Live figures over the last second (or the last samples).
struct LiveStats {
  std::deque<Clock::time_point> frames;
  std::deque<std::pair<Clock::time_point, std::uint64_t>> sim_sequences;
  std::deque<std::pair<Clock::time_point, std::uint64_t>> haptic_ticks;
  std::vector<double> periods;  // ring
  std::size_t period_next{0};
  std::uint64_t samples{0}, clamped{0}, invalid{0}, non_finite{0};
  double fps{0.0}, steps_per_s{0.0}, haptic_hz{0.0}, period_p50_ms{0.0}, period_p99_ms{0.0};
  // Over the whole run, not the last samples: one 20 ms stall is what a user feels, and a
  // percentile of the last 4,000 ticks forgets it within seconds.
  double longest_period_ms{0.0};
  std::uint64_t periods_over_2ms{0};
  Clock::time_point last_percentiles{};

  void add_period(double s) {
    longest_period_ms = std::max(longest_period_ms, 1e3 * s);
    if (s > 2e-3) ++periods_over_2ms;
    if (periods.size() < 4000) {
      periods.push_back(s);
    } else {
      periods[period_next] = s;
      period_next = (period_next + 1) % periods.size();
    }
  }
  void update(Clock::time_point now) {
    while (!frames.empty() && seconds_between(frames.front(), now) > 1.0) frames.pop_front();
    fps = static_cast<double>(frames.size()) /
          std::clamp(frames.empty() ? 1.0 : seconds_between(frames.front(), now), 0.25, 1.0);
    const auto rate = [&](auto& q) {
      while (q.size() > 2 && seconds_between(q.front().first, now) > 1.0) q.pop_front();
      if (q.size() < 2) return 0.0;
      const double span = seconds_between(q.front().first, q.back().first);
      return span > 0.0 ? static_cast<double>(q.back().second - q.front().second) / span : 0.0;
    };
    steps_per_s = rate(sim_sequences);
    haptic_hz = rate(haptic_ticks);
    if (seconds_between(last_percentiles, now) > 0.5 && !periods.empty()) {
      std::vector<double> sorted = periods;
      std::sort(sorted.begin(), sorted.end());
      period_p50_ms = 1e3 * sorted[sorted.size() / 2];
      period_p99_ms = 1e3 * sorted[std::min(sorted.size() - 1, sorted.size() * 99 / 100)];
      last_percentiles = now;
    }
  }
};

/// A stylus trajectory being recorded (the replay format, device frame) and the settings
/// changed meanwhile.
struct Recording {
  std::filesystem::path file;
  std::vector<haptics::ReplaySample> samples;
  std::vector<std::string> events;  // "t: what"
  double start_s{-1.0};             // haptic time of the first sample
  Eigen::Matrix4d world_to_device{Eigen::Matrix4d::Identity()};
  std::optional<scene::HofProject> project;  // the settings when it began (SOFA-based worlds)
  [[nodiscard]] double seconds() const { return samples.empty() ? 0.0 : samples.back().t_s; }
};

/// How the scene is drawn beyond the project's settings (not saved: debugging aids). The
/// Graphics panel edits it in place: it is the window's, not the world's.
struct ViewOptions {
  bool show_bound_tree{false};
  int bound_tree_depth{4};
  bool show_contact_triangle{true};
  bool show_fixed_nodes{false};
  bool show_device{true};
  bool show_regions{true};
  float arrow_m_per_n{0.0f};  // 0: automatic (an 8 N force as long as a third of the scene)
  /// Contacts: between bodies (points, force arrows) and the shaped tool's contact points.
  bool show_contacts{false};
  float contact_arrow_scale{1.0f};  // × the automatic length (the largest force a tenth of the scene)
};

/// A pair of bodies by world index, the smaller first.
using BodyPair = std::pair<std::int32_t, std::int32_t>;

/// The world on screen as the panels read it: references into the window, valid for one frame.
struct WorldView {
  const std::filesystem::path& file;
  const scene::HofProject& project;  ///< what a save writes (the file's, with the changes made here)
  const std::string& world_name;
  const std::string& length_unit;
  const std::string& device_spec;
  const coupling::Session* session;      ///< null: nothing open
  const procedures::NeedleTool* needle;  ///< the needle stylus, when the project mounts one
  bool mouse_stylus;                     ///< the mouse holds the stylus
  Vec3 stylus_target;                    ///< where the mouse stylus is sent (world)
  const haptics::Calibration& calibration;
  double max_force_n;
  double workspace_radius_m;
  const std::vector<BodyView>& bodies;
  const procedures::ShapedTool* tool;  ///< the tool with a shape on the stylus, when the project mounts one
  /// Contact between bodies: the session's settings, the pairs switched off, the last pass's
  /// contacts (null: none published yet).
  const coupling::ContactSettings& contact_settings;
  const std::set<BodyPair>& disabled_pairs;
  const coupling::BodyContactsView* contacts;
  Vec3 bounds_min, bounds_max;
  bool animating, dirty, realtime_pacing;
  // Telemetry.
  const haptics::HapticSample& last;
  const LiveStats& stats;
  const std::vector<float>& plot_force;        ///< the last kPlotSeconds, oldest first
  const std::vector<float>& plot_indentation;  ///< mm
  double indentation_m;
  bool reading;  ///< the device's latest tick had a reading
  std::int32_t contact_body;
  const Recording* recording;  ///< null: not recording
  // Messages.
  const std::string& error;
  const std::deque<std::string>& log;
  const render::OrbitCamera& camera;

  [[nodiscard]] double scene_size() const { return std::max((bounds_max - bounds_min).norm(), 1e-6); }
  /// The body's name, or `fallback` for an index that is none.
  [[nodiscard]] std::string body_name(std::int32_t i, const std::string& fallback) const {
    return i >= 0 && static_cast<std::size_t>(i) < bodies.size() ? bodies[static_cast<std::size_t>(i)].name : fallback;
  }
};

}  // namespace hof::app::gui
