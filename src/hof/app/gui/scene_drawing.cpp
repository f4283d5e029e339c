// The 3D scene: the bodies (opaque, then transparent), the shapes only seen, the needle, the
// debug views, the stylus with its proxy (or the tool with a shape at its pose), contact and
// force, and the contacts' debug view.
#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>

#include "hof/app/gui/detail/gui_window.h"
#include "hof/app/gui/detail/scene_drawing.h"

namespace hof::app::gui {

namespace {

// The project's render mode as the renderer's (scene/ does not depend on render/).
render::RenderMode render_mode_of(scene::RenderMode mode) {
  switch (mode) {
    case scene::RenderMode::kShaded:
      return render::RenderMode::kShaded;
    case scene::RenderMode::kWireframe:
      return render::RenderMode::kWireframe;
    case scene::RenderMode::kShadedWireframe:
      return render::RenderMode::kShadedWireframe;
    case scene::RenderMode::kPoints:
      return render::RenderMode::kPoints;
  }
  return render::RenderMode::kShaded;
}

}  // namespace

/// The twelve edges of the box [lo, hi] as line-segment end points, appended to `lines`.
void add_box_edges(std::vector<Vec3>& lines, const Vec3& lo, const Vec3& hi) {
  for (int a = 0; a < 3; ++a) {
    for (int c = 0; c < 4; ++c) {
      Vec3 p = lo;
      const int b1 = (a + 1) % 3, b2 = (a + 2) % 3;
      p[b1] = (c & 1) ? hi[b1] : lo[b1];
      p[b2] = (c & 2) ? hi[b2] : lo[b2];
      Vec3 q = p;
      q[a] = hi[a];
      lines.push_back(p);
      lines.push_back(q);
    }
  }
}

// The colour of each needle phase (the tip marker, the touch panel).
render::Rgba phase_colour(procedures::NeedlePhase phase) {
  switch (phase) {
    case procedures::NeedlePhase::kTouching:
      return {1.0f, 0.85f, 0.1f, 1.0f};
    case procedures::NeedlePhase::kPrePuncture:
      return {0.75f, 0.35f, 1.0f, 1.0f};
    case procedures::NeedlePhase::kPunctured:
      return {0.1f, 0.8f, 0.5f, 1.0f};
    case procedures::NeedlePhase::kRelaxation:
      return {0.35f, 0.75f, 1.0f, 1.0f};
    case procedures::NeedlePhase::kExtraction:
      return {1.0f, 0.6f, 0.1f, 1.0f};
    default:
      return {0.85f, 0.85f, 0.85f, 1.0f};
  }
}

void GuiWindow::draw_scene(int width, int height) {
  view_x_ = static_cast<int>(kPanelWidth);
  view_w_ = std::max(width - view_x_, 1);
  view_h_ = std::max(height, 1);
  glViewport(0, 0, width, height);
  glClearColor(0.12f, 0.13f, 0.15f, 1.0f);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  renderer_->begin(camera_, view_x_, 0, view_w_, view_h_, render::Rgba(0.16f, 0.18f, 0.22f, 1.0f));

  const scene::GraphicsSetup& g = project_.graphics;
  render::Lighting lighting;
  lighting.headlight_intensity = g.headlight ? static_cast<float>(g.headlight_intensity) : 0.0f;
  lighting.direction = g.light_direction.cast<float>();
  lighting.intensity = static_cast<float>(g.light_intensity);
  lighting.ambient = static_cast<float>(g.ambient_intensity);
  renderer_->set_lighting(lighting);
  draw_bodies();
  draw_debug_views();
  draw_stylus();
  if (view_options_.show_contacts) draw_contacts(scene_size());
  glViewport(0, 0, width, height);
}

void GuiWindow::draw_bodies() {
  const scene::GraphicsSetup& g = project_.graphics;
  render::Material tissue;
  tissue.diffuse = render::Rgba(static_cast<float>(g.diffuse_color.x()), static_cast<float>(g.diffuse_color.y()),
                                static_cast<float>(g.diffuse_color.z()), static_cast<float>(1.0 - g.transparency));
  tissue.specular = g.specular_color.cast<float>();
  tissue.shininess = static_cast<float>(g.shininess);
  render::Material rigid;
  rigid.diffuse = render::Rgba(0.62f, 0.64f, 0.68f, 1.0f);
  rigid.specular = {0.3f, 0.3f, 0.3f};
  const render::RenderMode mode = render_mode_of(g.render_mode);
  const double size = scene_size();
  // Opaque parts first, then transparent ones (shapes only seen among them).
  for (int pass = 0; pass < 2; ++pass) {
    // The needle is opaque: drawn before the transparent bodies it is seen through.
    if (pass == 1 && last_.valid && needle_) draw_needle(size);
    for (const VisualView& v : visuals_) {
      if ((v.material.diffuse.w() < 0.999f) == (pass == 1))
        renderer_->draw(v.mesh, v.material, render::RenderMode::kShaded);
    }
    for (LayerView& l : layers_) {
      for (const haptics::SurfacePart& part : l.parts) {
        const BodyView* body = part.body >= 0 && static_cast<std::size_t>(part.body) < bodies_.size()
                                   ? &bodies_[static_cast<std::size_t>(part.body)]
                                   : nullptr;
        const render::Material& m = body && body->material ? *body->material : part.is_static ? rigid : tissue;
        if ((m.diffuse.w() < 0.999f) != (pass == 1)) continue;
        renderer_->draw(l.mesh, m, part.is_static ? render::RenderMode::kShaded : mode, Eigen::Matrix4f::Identity(),
                        static_cast<std::size_t>(part.first_triangle), static_cast<std::size_t>(part.triangle_count));
      }
    }
  }
  if (last_.valid && needle_ && last_.tool.touched) {
    // The needle inside a body, seen through it (as an X-ray): the path from the entry point to
    // the tip and the tip marker, over everything.
    glDisable(GL_DEPTH_TEST);
    const haptics::ToolState& t = last_.tool;
    const Vec3 path[2] = {t.entry, last_.device};
    renderer_->draw_lines(path, render::Rgba(0.9f, 0.92f, 0.95f, 1.0f));
    renderer_->draw_sphere(last_.device, 0.004 * size, phase_colour(static_cast<procedures::NeedlePhase>(t.phase)));
    renderer_->draw_sphere(t.entry, 0.004 * size, render::Rgba(1.0f, 0.15f, 0.1f, 1.0f));
    glEnable(GL_DEPTH_TEST);
  }
}

void GuiWindow::draw_debug_views() {
  const double size = scene_size();
  // Debug views.
  if (view_options_.show_bound_tree) {
    std::vector<Vec3> lines;
    for (const LayerView& l : layers_) {
      if (!l.latest) continue;
      for (const auto& [lo, hi] : l.latest->tree.boxes(view_options_.bound_tree_depth)) add_box_edges(lines, lo, hi);
    }
    renderer_->draw_lines(lines, render::Rgba(0.3f, 0.9f, 0.4f, 1.0f));
  }
  if (view_options_.show_fixed_nodes) {
    for (const BodyView& b : bodies_)
      renderer_->draw_points(b.fixed_points, render::Rgba(0.2f, 0.6f, 1.0f, 1.0f), 5.0f);
  }
  if (view_options_.show_regions) {
    for (const scene::MaterialRegion& r : project_.regions) {
      if (r.shape == scene::MaterialRegion::Shape::kSphere) {
        renderer_->draw_sphere(r.center, r.radius, render::Rgba(1.0f, 0.55f, 0.1f, 0.3f));
        continue;
      }
      if (r.shape != scene::MaterialRegion::Shape::kBox) continue;  // a physical group has no shape of its own
      std::vector<Vec3> lines;
      add_box_edges(lines, r.box_min, r.box_max);
      renderer_->draw_lines(lines, render::Rgba(1.0f, 0.55f, 0.1f, 1.0f));
    }
  }
  // Spring effects: the anchor, and the sphere within which the spring catches the stylus.
  for (const haptics::SpringEffect& e : project_.effects.springs) {
    renderer_->draw_sphere(e.position_m, std::max(0.003 * size, 1e-6), render::Rgba(0.3f, 0.9f, 0.5f, 1.0f));
    renderer_->draw_sphere(e.position_m, e.start_distance_m, render::Rgba(0.3f, 0.9f, 0.5f, 0.25f));
  }
}

void GuiWindow::draw_stylus() {
  const double size = scene_size();
  // The stylus, the proxy, the device, the contact.
  const double proxy_radius = std::max(
      project_.renderer == haptics::RendererKind::kRuspini ? project_.proxy_radius_m : project_.stylus_radius_m,
      0.004 * size);
  if (last_.valid && shaped_tool_ && last_.tool.active) {
    draw_tool(size);
    return;
  }
  if (last_.valid && !needle_) {
    const Vec3 shaft = (camera_.up_on_screen() * 0.8 - camera_.forward() * 0.6).normalized();
    const double length = std::clamp(project_.stylus_length_m, 0.05 * size, 0.6 * size);
    renderer_->draw_cylinder(last_.proxy, last_.proxy + shaft * length, proxy_radius * 0.45,
                             render::Rgba(0.75f, 0.78f, 0.82f, 1.0f));
    renderer_->draw_sphere(last_.proxy, proxy_radius, render::Rgba(0.35f, 0.75f, 1.0f, 1.0f));
    if (view_options_.show_device) {
      renderer_->draw_sphere(last_.device, proxy_radius * 0.6, render::Rgba(0.95f, 0.95f, 0.3f, 1.0f));
      const Vec3 segment[2] = {last_.proxy, last_.device};
      renderer_->draw_lines(segment, render::Rgba(0.95f, 0.95f, 0.3f, 1.0f));
    }
    if (last_.contact) {
      renderer_->draw_sphere(last_.contact_point, proxy_radius * 0.5, render::Rgba(1.0f, 0.85f, 0.1f, 1.0f));
      const Vec3 normal[2] = {last_.contact_point, last_.contact_point + last_.contact_normal * 0.08 * size};
      renderer_->draw_lines(normal, render::Rgba(0.3f, 1.0f, 0.3f, 1.0f));
      const double per_n =
          view_options_.arrow_m_per_n > 0.0f ? view_options_.arrow_m_per_n : size / 3.0 / std::max(max_force_n_, 1e-6);
      const Vec3 force = last_.force;
      if (force.norm() > 1e-6) {
        renderer_->draw_arrow(last_.proxy, last_.proxy + force * per_n, proxy_radius * 0.35,
                              render::Rgba(1.0f, 0.25f, 0.2f, 1.0f));
      }
      if (view_options_.show_contact_triangle && last_.triangle >= 0 &&
          static_cast<std::size_t>(last_.layer) < layers_.size()) {
        const haptics::SurfaceSnapshot* s = layers_[static_cast<std::size_t>(last_.layer)].latest;
        if (s && static_cast<std::size_t>(last_.triangle) < s->triangles.size()) {
          const mesh::Tri& t = s->triangles[static_cast<std::size_t>(last_.triangle)];
          const Vec3 lift = last_.contact_normal * 0.001 * size;
          const Vec3 a = s->vertices[static_cast<std::size_t>(t[0])] + lift,
                     b = s->vertices[static_cast<std::size_t>(t[1])] + lift,
                     c = s->vertices[static_cast<std::size_t>(t[2])] + lift;
          const Vec3 edges[6] = {a, b, b, c, c, a};
          renderer_->draw_lines(edges, render::Rgba(0.2f, 1.0f, 1.0f, 1.0f));
        }
      }
    }
  }
}

void GuiWindow::draw_needle(double size) {
  // The thesis' stylus (Zamani et al.): a thin tip section, the shaft, then the syringe, drawn
  // from the tip back along the needle. Inside a body the needle lies on its insertion axis;
  // outside, it points into the view. Diameters below what a screen shows are widened, in
  // proportion.
  const procedures::NeedleGeometry& g = project_.needle ? project_.needle->geometry : procedures::NeedleGeometry{};
  const haptics::ToolState& tool = last_.tool;
  const auto phase = static_cast<procedures::NeedlePhase>(tool.phase);
  const bool inside = tool.touched && tool.axis.squaredNorm() > 0.5;
  const Vec3 back =
      inside ? Vec3(-tool.axis) : Vec3((camera_.up_on_screen() * 0.8 - camera_.forward() * 0.6).normalized());
  const Vec3 tip = last_.device;
  const double visible = 0.0012 * size;  // the thinnest radius worth drawing
  const double widen = std::max(1.0, visible / (0.5 * g.tip_diameter_m));
  const Vec3 tip_end = tip + back * g.tip_length_m;
  const Vec3 hub = tip + back * g.length_m;
  renderer_->draw_cylinder(tip, tip_end, 0.5 * g.tip_diameter_m * widen, render::Rgba(0.85f, 0.87f, 0.9f, 1.0f));
  renderer_->draw_cylinder(
      tip_end, hub,
      0.5 * g.shaft_diameter_m * std::min(widen, std::max(1.0, 2.0 * visible / (0.5 * g.shaft_diameter_m))),
      render::Rgba(0.75f, 0.78f, 0.82f, 1.0f));
  renderer_->draw_cylinder(hub, hub + back * g.syringe_length_m, 0.5 * g.syringe_diameter_m,
                           render::Rgba(0.8f, 0.9f, 1.0f, 0.45f));
  // The tip marker (the thesis' sphere at the tip), in the phase's colour, and the entry point.
  renderer_->draw_sphere(tip, std::max(0.0025 * size, g.tip_diameter_m), phase_colour(phase));
  if (tool.touched) {
    renderer_->draw_sphere(tool.entry, std::max(0.003 * size, g.shaft_diameter_m),
                           render::Rgba(1.0f, 0.15f, 0.1f, 1.0f));
    const Vec3 path[2] = {tool.entry, tool.entry + tool.axis * std::max(tool.depth_m, 0.0)};
    renderer_->draw_lines(path, render::Rgba(1.0f, 0.4f, 0.3f, 1.0f));
  }
  const double per_n =
      view_options_.arrow_m_per_n > 0.0f ? view_options_.arrow_m_per_n : size / 3.0 / std::max(max_force_n_, 1e-6);
  if (last_.force.norm() > 1e-6) {
    renderer_->draw_arrow(hub, hub + last_.force * per_n, 0.0015 * size, render::Rgba(1.0f, 0.25f, 0.2f, 1.0f));
  }
}

void GuiWindow::draw_tool(double size) {
  // The tool where its proxy is (the shape never ends a tick inside a surface), turned as the
  // hand turns it; the device point (where the hand is) and the coupling between them.
  const haptics::ToolState& t = last_.tool;
  const Mat3 r = t.orientation.normalized().toRotationMatrix();
  const Vec3 tip = t.tip;
  const bool touching = t.contact_count > 0;
  const render::Rgba steel =
      touching ? render::Rgba(0.95f, 0.78f, 0.45f, 1.0f) : render::Rgba(0.78f, 0.8f, 0.84f, 1.0f);
  if (tool_mesh_) {
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
    pose.topLeftCorner<3, 3>() = r.cast<float>();
    pose.topRightCorner<3, 1>() = tip.cast<float>();
    render::Material m;
    m.diffuse = steel;
    m.specular = {0.5f, 0.5f, 0.5f};
    m.shininess = 0.5f;
    renderer_->draw(*tool_mesh_, m, render::RenderMode::kShaded, pose);
  } else {
    for (const procedures::ToolPrimitive& p : shaped_tool_->primitives()) {
      const Vec3 a = tip + r * p.a, b = tip + r * p.b;
      renderer_->draw_sphere(a, p.radius, steel);
      if ((b - a).norm() > 1e-12) {
        renderer_->draw_cylinder(a, b, p.radius, steel);
        renderer_->draw_sphere(b, p.radius, steel);
      }
    }
  }
  if (shaped_tool_->config().shape == procedures::ToolShape::kSphere) {
    // A sphere shows no turn of its own: a thin handle along its +z (the shaft's side) does.
    const double radius = shaped_tool_->primitives().front().radius;
    renderer_->draw_cylinder(tip + r * Vec3(0, 0, radius), tip + r * Vec3(0, 0, radius + 0.15 * size),
                             std::max(0.2 * radius, 0.0015 * size), render::Rgba(0.6f, 0.62f, 0.66f, 1.0f));
  }
  if (view_options_.show_device) {
    const double marker = std::max(0.0025 * size, 0.3 * t.radius);
    renderer_->draw_sphere(last_.device, marker, render::Rgba(0.95f, 0.95f, 0.3f, 1.0f));
    const Vec3 segment[2] = {tip, last_.device};
    renderer_->draw_lines(segment, render::Rgba(0.95f, 0.95f, 0.3f, 1.0f));
  }
  const double per_n =
      view_options_.arrow_m_per_n > 0.0f ? view_options_.arrow_m_per_n : size / 3.0 / std::max(max_force_n_, 1e-6);
  if (last_.force.norm() > 1e-6) {
    renderer_->draw_arrow(tip, tip + last_.force * per_n, std::max(0.0015 * size, 0.3 * t.radius),
                          render::Rgba(1.0f, 0.25f, 0.2f, 1.0f));
  }
}

void GuiWindow::draw_contacts(double size) {
  // Over everything (contacts lie between bodies, inside what is drawn): each contact's two
  // points, and the force on its first body as an arrow, the largest a tenth of the scene.
  glDisable(GL_DEPTH_TEST);
  if (contacts_ && !contacts_->contacts.empty()) {
    double largest = 0.0;
    for (const coupling::BodyContactView& c : contacts_->contacts) largest = std::max(largest, c.force_on_a_n.norm());
    const double per_n = largest > 0.0 ? view_options_.contact_arrow_scale * 0.1 * size / largest : 0.0;
    std::vector<Vec3> a_points, b_points;
    for (const coupling::BodyContactView& c : contacts_->contacts) {
      a_points.push_back(c.point_a);
      b_points.push_back(c.point_b);
    }
    renderer_->draw_points(a_points, render::Rgba(1.0f, 0.6f, 0.1f, 1.0f), 7.0f);
    renderer_->draw_points(b_points, render::Rgba(0.3f, 0.8f, 1.0f, 1.0f), 7.0f);
    for (const coupling::BodyContactView& c : contacts_->contacts) {
      const Vec3 arrow = c.force_on_a_n * per_n;
      // An arrow thinner as it is shorter, so that its head never hides its length; forces
      // below a twentieth of the largest (at the automatic length) are left as points.
      const double length = arrow.norm();
      if (length < 0.005 * size) continue;
      renderer_->draw_arrow(c.point_a, c.point_a + arrow, std::min(0.003 * size, 0.06 * length),
                            render::Rgba(1.0f, 0.45f, 0.1f, 1.0f));
    }
  }
  if (shaped_tool_ && last_.valid && last_.tool.active) {
    // The tool's contact points: where its shape, at its pose, meets a surface (the test its
    // tick makes: each part's distance to the triangles near it, within a hair of its radius).
    const haptics::ToolState& t = last_.tool;
    const Mat3 r = t.orientation.normalized().toRotationMatrix();
    near_triangles_.resize(4096);
    std::vector<Vec3> points;
    for (const LayerView& l : layers_) {
      const haptics::SurfaceSnapshot* s = l.latest;
      if (!s || s->triangles.empty()) continue;
      for (const procedures::ToolPrimitive& p : shaped_tool_->primitives()) {
        const Vec3 a = t.tip + r * p.a, b = t.tip + r * p.b;
        const double reach = 0.5 * (b - a).norm() + p.radius * 1.05;
        const std::size_t found =
            std::min(s->tree.triangles_near(0.5 * (a + b), reach, near_triangles_), near_triangles_.size());
        for (std::size_t k = 0; k < found; ++k) {
          const mesh::Tri& tri = s->triangles[static_cast<std::size_t>(near_triangles_[k])];
          Vec3 on_segment, on_triangle, weights;
          const double d = procedures::closest_segment_triangle(
              a, b, s->vertices[static_cast<std::size_t>(tri[0])], s->vertices[static_cast<std::size_t>(tri[1])],
              s->vertices[static_cast<std::size_t>(tri[2])], on_segment, on_triangle, weights);
          if (d <= p.radius * 1.05) points.push_back(on_triangle);
        }
      }
    }
    renderer_->draw_points(points, render::Rgba(0.2f, 1.0f, 0.4f, 1.0f), 6.0f);
  }
  glEnable(GL_DEPTH_TEST);
}

}  // namespace hof::app::gui
