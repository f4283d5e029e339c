// What the loops published, taken in once a frame: every haptic tick's telemetry (figures,
// plots, the recording, the needle's events) and the latest shapes (uploaded, coloured by
// displacement, strain or von Mises stress).
#include <fmt/format.h>

#include <algorithm>

#include "hof/app/gui/detail/gui_window.h"
#include "hof/mesh/surface_strain.h"
#include "hof/render/colormap.h"

namespace hof::app::gui {

void GuiWindow::update_from_loops() {
  if (!session_) return;
  const auto now = Clock::now();
  // Telemetry: every tick since the last frame.
  std::uint64_t last_tick = 0;
  bool any = false;
  session_->poll([&](const haptics::HapticSample& s) {
    any = true;
    last_tick = s.tick;
    take_sample(s);
  });
  if (any) stats_.haptic_ticks.emplace_back(now, last_tick);
  // The latest shapes.
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    auto& buffer = session_->graphics_surfaces(l);
    if (buffer.acquire()) {
      upload_layer(layers_[l], buffer.read());
      max_displacement_seen_m_ = std::max(max_displacement_seen_m_, layers_[l].max_displacement_m);
    } else {
      layers_[l].latest = &buffer.read();
    }
  }
  update_stress();
  if (contact_settings_.enabled) {
    // Published from this first call on; read without a lock (a triple buffer).
    auto& contacts = session_->graphics_contacts();
    contacts.acquire();
    contacts_ = &contacts.read();
  }
  if (calibration_pending_ && session_->calibrations_applied() >= calibrations_submitted_) {
    calibration_pending_ = false;
    if (mouse_) mouse_->place((calibration_.position.inverse() * mouse_world_.homogeneous()).head<3>());
  }
  stats_.sim_sequences.emplace_back(now, session_->steps_taken());
  stats_.frames.push_back(now);
  stats_.update(now);
  if (session_->simulation_ended()) {
    const coupling::SessionReport r = session_->stop_realtime();
    report(fmt::format("the simulation stopped: {} — change a setting and press Reset",
                       r.divergence.empty() ? "it ended" : r.divergence),
           true);
    // The haptic loop has stopped with it (zero force sent); Reset starts both again.
  }
}

void GuiWindow::take_sample(const haptics::HapticSample& s) {
  ++stats_.samples;
  reading_ = s.valid;
  if (!s.valid) {
    ++stats_.invalid;
    return;
  }
  if (!s.force.allFinite() || !s.requested_force.allFinite()) ++stats_.non_finite;
  // At the device's force limit (a fade-in after a device switch lowers the force too, but
  // is not the limit).
  if (s.requested_force.norm() > s.force.norm() + 1e-9 && s.force.norm() >= 0.999 * force_limit_n()) ++stats_.clamped;
  if (s.period_s > 0.0) stats_.add_period(s.period_s);
  if (recording_) {
    Recording& r = *recording_;
    if (r.start_s < 0.0) r.start_s = s.time_s;
    const double t = s.time_s - r.start_s;
    if (r.samples.empty() || t > r.samples.back().t_s) {
      haptics::ReplaySample sample;
      sample.t_s = t;
      sample.position_m = (r.world_to_device * s.device.homogeneous()).head<3>();
      sample.buttons = s.buttons;
      r.samples.push_back(sample);
    }
  }
  max_force_seen_n_ = std::max(max_force_seen_n_, s.force.norm());
  if (s.contact) ++contact_ticks_;
  // Indentation: as `hof run` (telemetry.csv) counts it, from where the contact began.
  double indentation = 0.0;
  if (s.contact && s.triangle >= 0) {
    const double from_rest =
        (session_->rest_point(s.triangle, s.barycentric, s.layer) - s.contact_point).dot(s.contact_normal);
    if (!was_in_contact_) displaced_at_contact_ = from_rest;
    indentation = from_rest - displaced_at_contact_;
    contact_body_ = session_->body_of_triangle(s.triangle, s.layer);
  }
  was_in_contact_ = s.contact && s.triangle >= 0;
  indentation_m_ = indentation;
  if (needle_ && s.tool.active) {
    // The needle's events, in the messages (the thesis' field network as a log).
    const auto phase = static_cast<procedures::NeedlePhase>(s.tool.phase);
    const std::string body = s.tool.body >= 0 && static_cast<std::size_t>(s.tool.body) < bodies_.size()
                                 ? bodies_[static_cast<std::size_t>(s.tool.body)].name
                                 : std::string("the body");
    const double shown = 1e3;  // the needle's lengths are SI
    const char* unit = "mm";
    if (phase == procedures::NeedlePhase::kPunctured && needle_phase_ == procedures::NeedlePhase::kPrePuncture) {
      report(fmt::format("needle: the capsule of {} broke at {:.1f} {} ({:.3f} N after)", body, shown * s.tool.depth_m,
                         unit, s.tool.axial_force_n),
             false);
    } else if (phase == procedures::NeedlePhase::kTouching && needle_phase_ != procedures::NeedlePhase::kTouching) {
      report(fmt::format("needle: touching {}", body), false);
    } else if (phase == procedures::NeedlePhase::kOut && needle_phase_ != procedures::NeedlePhase::kOut) {
      report("needle: withdrawn", false);
    }
    needle_phase_ = phase;
    indentation = s.tool.depth_m;  // the second plot shows the depth
  }
  // A plot point is the mean of |F| over the ticks since the last point (a box filter before
  // keeping one point in ten): one tick picked out of a rippling force drew spikes that the
  // hand never felt and the telemetry's plots do not show.
  plot_force_sum_n_ += s.force.norm();
  ++plot_force_ticks_;
  if (s.time_s >= next_plot_time_) {
    next_plot_time_ = s.time_s + 1.0 / kPlotRateHz;
    std::rotate(plot_force_.begin(), plot_force_.begin() + 1, plot_force_.end());
    std::rotate(plot_indentation_.begin(), plot_indentation_.begin() + 1, plot_indentation_.end());
    plot_force_.back() = static_cast<float>(plot_force_sum_n_ / static_cast<double>(plot_force_ticks_));
    plot_force_sum_n_ = 0.0;
    plot_force_ticks_ = 0;
    plot_indentation_.back() = static_cast<float>(1e3 * indentation);
  }
  last_ = s;
}

void GuiWindow::upload_layer(LayerView& layer, const haptics::SurfaceSnapshot& s) {
  layer.latest = &s;
  layer.mesh.set_positions(s.vertices);
  layer.mesh.set_normals(s.vertex_normals);
  layer.max_displacement_m = 0.0;
  if (layer.rest.size() == s.vertices.size()) {
    for (std::size_t i = 0; i < s.vertices.size(); ++i)
      layer.max_displacement_m = std::max(layer.max_displacement_m, (s.vertices[i] - layer.rest[i]).norm());
  }
  using scene::ColorBy;
  const ColorBy by = project_.graphics.color_by;
  if (by == ColorBy::kMaterial || layer.rest.size() != s.vertices.size() ||
      (by == ColorBy::kStress && layer.stress.size() != s.vertices.size())) {
    if (layer.mesh.has_colours()) layer.mesh.set_colours({});
    return;
  }
  // A scale that grows with the field and has a floor (1 % of the scene; 1 % strain), so that a
  // still body does not flicker through the colour map.
  layer.colours.resize(s.vertices.size());
  if (by == ColorBy::kStrain) {
    mesh::vertex_strain_magnitude(layer.rest, s.vertices, s.triangles, layer.strain);
    // The scale: the 98th percentile, not the maximum — a point load strains the triangles
    // under it far more than the rest, which would leave the whole body one colour.
    layer.ranked = layer.strain;
    const auto at =
        layer.ranked.begin() + static_cast<std::ptrdiff_t>(0.98 * static_cast<double>(layer.ranked.size() - 1));
    std::nth_element(layer.ranked.begin(), at, layer.ranked.end());
    layer.max_strain = layer.ranked.empty() ? 0.0 : *at;
  }
  const double range = by == ColorBy::kStrain   ? std::max(layer.max_strain, 0.01)
                       : by == ColorBy::kStress ? std::max(layer.max_stress_pa, 1e-6)
                                                : std::max(layer.max_displacement_m, 0.01 * scene_size());
  for (std::size_t i = 0; i < s.vertices.size(); ++i) {
    const double value = by == ColorBy::kStrain   ? layer.strain[i]
                         : by == ColorBy::kStress ? layer.stress[i]
                                                  : (s.vertices[i] - layer.rest[i]).norm();
    const Eigen::Vector3f c = render::viridis(static_cast<float>(value / range));
    layer.colours[i] = render::Rgba(c.x(), c.y(), c.z(), 1.0f);
  }
  layer.mesh.set_colours(layer.colours);
}

void GuiWindow::update_stress() {
  // Von Mises stress from the bodies' node positions, on this thread, ten times a second.
  if (project_.graphics.color_by != scene::ColorBy::kStress || !session_) return;
  auto& states = session_->graphics_states();
  const auto now = Clock::now();
  if (now < next_stress_) return;
  if (!states.acquire() && !layers_.empty() && !layers_[0].stress.empty()) return;
  next_stress_ = now + std::chrono::milliseconds(100);
  const std::vector<std::vector<double>>& x = states.read();
  for (LayerView& layer : layers_) layer.stress.assign(layer.rest.size(), 0.0);
  std::vector<double> node_values;
  std::vector<Vec3> surface;
  for (std::size_t i = 0; i < bodies_.size() && i < x.size(); ++i) {
    BodyView& b = bodies_[i];
    if (!b.structure || x[i].size() != 3 * b.structure->positions.size()) continue;
    if (!b.stress) b.stress = std::make_shared<mechanics::VonMisesStress>(current_config(b));
    if (!b.stress->available()) continue;
    b.stress->node_stress(x[i], b.node_stress);
    // Node values to the surface through the body's own mapping (a scalar in x).
    node_values.assign(3 * b.node_stress.size(), 0.0);
    for (std::size_t n = 0; n < b.node_stress.size(); ++n) node_values[3 * n] = b.node_stress[n];
    const coupling::SurfaceMapping& mapping = session_->body(i).mapping;
    surface.resize(mapping.surface_vertex_count());
    mapping.apply(node_values, surface);
    if (static_cast<std::size_t>(b.layer) >= layers_.size()) continue;
    LayerView& layer = layers_[static_cast<std::size_t>(b.layer)];
    for (const haptics::SurfacePart& part : layer.parts) {
      if (part.body != static_cast<std::int32_t>(i) || static_cast<std::size_t>(part.vertex_count) != surface.size())
        continue;
      for (std::size_t v = 0; v < surface.size(); ++v)
        layer.stress[static_cast<std::size_t>(part.first_vertex) + v] = std::max(surface[v].x(), 0.0);
    }
  }
  for (LayerView& layer : layers_) {
    // The scale: the 98th percentile, as for strain (the load point peaks far above the rest).
    layer.ranked = layer.stress;
    if (layer.ranked.empty()) continue;
    const auto at =
        layer.ranked.begin() + static_cast<std::ptrdiff_t>(0.98 * static_cast<double>(layer.ranked.size() - 1));
    std::nth_element(layer.ranked.begin(), at, layer.ranked.end());
    layer.max_stress_pa = *at;
    if (layer.latest) upload_layer(layer, *layer.latest);
  }
}

}  // namespace hof::app::gui
