// X3D (H3D API) scene reader: every anchor scene from H3D's examples and settings loads; the
// haptic content of each (surfaces, options, effects, devices, FitToBox, DeformableShape) is
// what the files say; DEF/USE, transforms and face sets on small inline scenes; malformed
// scenes fail with the file and line.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>

#include "hof/scene/x3d_scene.h"

namespace hof::scene {
namespace {

namespace fs = std::filesystem;
using haptics::SurfaceKind;

const fs::path kH3d = fs::path(HOF_ANCHORS_DIR) / "h3d";
const fs::path kExamples = kH3d / "examples" / "All";
constexpr double kTol = 1e-9;

X3dScene load(const fs::path& path) {
  auto s = read_x3d_scene(path);
  EXPECT_TRUE(s.has_value()) << (s ? "" : s.error().to_string());
  return s ? std::move(*s) : X3dScene{};
}

bool contains(const std::vector<std::string>& v, std::string_view needle) {
  return std::ranges::any_of(v, [&](const std::string& s) { return s.find(needle) != std::string::npos; });
}

Eigen::AlignedBox3d bounds(const mesh::TriMesh& m) {
  Eigen::AlignedBox3d b;
  for (const Vec3& v : m.vertices) b.extend(v);
  return b;
}

// Writes `text` to a fresh file in the test temp folder and returns its path.
fs::path write_temp(const std::string& name, const std::string& text) {
  const fs::path dir = fs::temp_directory_path() / "hof_x3d_scene_test";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << text;
  return p;
}

bool same(const haptics::SurfaceMaterial& a, const haptics::SurfaceMaterial& b) {
  return a.kind == b.kind && a.stiffness == b.stiffness && a.damping_n_s_per_m == b.damping_n_s_per_m &&
         a.use_relative_values == b.use_relative_values && a.static_friction == b.static_friction &&
         a.dynamic_friction == b.dynamic_friction && a.snap_distance_m == b.snap_distance_m;
}

TEST(X3dScene, EveryAnchorSceneLoads) {
  int count = 0;
  for (const fs::path& dir : {kExamples, kH3d / "settings"}) {
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      if (!entry.is_regular_file() || entry.path().extension() != ".x3d") continue;
      auto s = read_x3d_scene(entry.path());
      EXPECT_TRUE(s.has_value()) << entry.path() << ": " << (s ? "" : s.error().to_string());
      ++count;
    }
  }
  EXPECT_GE(count, 12);
}

TEST(X3dScene, SurfacesKindsAndValues) {
  X3dScene s = load(kExamples / "Surfaces.x3d");
  std::erase_if(s.shapes, [](const X3dShape& shape) { return shape.geometry_type != "Sphere"; });  // the labels
  ASSERT_EQ(s.shapes.size(), 6u);
  for (const auto& shape : s.shapes) {
    EXPECT_TRUE(shape.touchable);
    EXPECT_EQ(shape.geometry_type, "Sphere");
    EXPECT_TRUE(shape.diffuse_color.isApprox(Vec3(0.8, 0.8, 0.8)));  // Material USE='M', default
  }
  const auto& smooth = s.shapes[0].surface;
  EXPECT_EQ(s.shapes[0].surface_type, "SmoothSurface");
  EXPECT_EQ(smooth.kind, SurfaceKind::kSmooth);
  EXPECT_DOUBLE_EQ(smooth.stiffness, 0.6);
  EXPECT_DOUBLE_EQ(smooth.damping_n_s_per_m, 0.5);
  EXPECT_TRUE(smooth.use_relative_values);
  EXPECT_FALSE(smooth.has_friction());

  const auto& frictional = s.shapes[1].surface;
  EXPECT_EQ(frictional.kind, SurfaceKind::kFrictional);
  EXPECT_DOUBLE_EQ(frictional.static_friction, 0.8);
  EXPECT_DOUBLE_EQ(frictional.dynamic_friction, 0.4);
  EXPECT_DOUBLE_EQ(frictional.stiffness, 0.6);

  const auto& magnetic = s.shapes[2].surface;
  EXPECT_EQ(magnetic.kind, SurfaceKind::kMagnetic);
  EXPECT_DOUBLE_EQ(magnetic.static_friction, 0.0);
  EXPECT_DOUBLE_EQ(magnetic.snap_distance_m, 0.01);

  // OpenHapticsSurface derives from MagneticSurface, with `magnetic` false by default
  // (h3d-nodes.md): a frictional surface with MagneticSurface's defaults.
  EXPECT_EQ(s.shapes[3].surface_type, "OpenHapticsSurface");
  EXPECT_EQ(s.shapes[3].surface.kind, SurfaceKind::kFrictional);
  EXPECT_DOUBLE_EQ(s.shapes[3].surface.stiffness, 0.5);
  EXPECT_DOUBLE_EQ(s.shapes[3].surface.static_friction, 0.1);
  // DepthMap and HapticTextures surfaces are frictional (their maps are not modelled).
  EXPECT_EQ(s.shapes[4].surface.kind, SurfaceKind::kFrictional);
  EXPECT_EQ(s.shapes[5].surface.kind, SurfaceKind::kFrictional);
  EXPECT_DOUBLE_EQ(s.shapes[5].surface.damping_n_s_per_m, 0.5);
  EXPECT_DOUBLE_EQ(s.shapes[5].surface.static_friction, 0.0);

  // The first sphere (r 0.06) sits at its Transform's translation.
  const auto b = bounds(s.shapes[0].mesh_W);
  EXPECT_NEAR(b.center().x(), -0.18, 1e-9);
  EXPECT_NEAR(b.center().y(), 0.08, 1e-9);
  EXPECT_NEAR(b.max().x(), -0.12, 1e-9);

  // The labels are instances of the ExternProto 'Text' (Prototype.x3d beside the scene).
  EXPECT_FALSE(contains(s.unsupported, "ProtoInstance"));
  // Text is in the PROTO's body: named with the file its line is in.
  EXPECT_TRUE(contains(s.unsupported, "Text (Prototype.x3d line 26)"));
  EXPECT_TRUE(contains(s.unsupported, "ImageTexture 'I' (line"));
  // The list of nodes not modelled, and once per surface HoF approximates what it renders.
  EXPECT_EQ(s.warnings.size(), 4u);
  EXPECT_TRUE(contains(s.warnings, "DepthMapSurface: rendered as a frictional surface: its depth map is not modelled"));
}

TEST(X3dScene, HapticsOptionsPerGeometryAndSharedAppearance) {
  const X3dScene s = load(kExamples / "HapticsOptions.x3d");
  ASSERT_EQ(s.shapes.size(), 2u);
  ASSERT_TRUE(s.shapes[0].haptics_options && s.shapes[1].haptics_options);
  EXPECT_EQ(s.shapes[0].haptics_options->touchable_face, X3dTouchableFace::kAsGraphics);
  EXPECT_EQ(s.shapes[1].haptics_options->touchable_face, X3dTouchableFace::kFront);
  EXPECT_DOUBLE_EQ(s.shapes[0].haptics_options->max_distance_m, 0.01);
  EXPECT_DOUBLE_EQ(s.shapes[1].haptics_options->max_distance_m, 0.3);
  EXPECT_DOUBLE_EQ(s.shapes[1].haptics_options->look_ahead_factor, 3.0);
  // Appearance USE='A': the same FrictionalSurface with H3D defaults.
  for (const auto& shape : s.shapes) {
    EXPECT_TRUE(shape.touchable);
    EXPECT_EQ(shape.geometry_type, "Cone");
    EXPECT_FALSE(shape.solid);
    EXPECT_EQ(shape.surface.kind, SurfaceKind::kFrictional);
    EXPECT_DOUBLE_EQ(shape.surface.stiffness, 0.5);
    EXPECT_DOUBLE_EQ(shape.surface.static_friction, 0.1);
    EXPECT_DOUBLE_EQ(shape.surface.dynamic_friction, 0.4);
  }
  ASSERT_TRUE(s.global_settings && s.global_settings->debug);
  EXPECT_TRUE(s.global_settings->debug->draw_haptic_triangles);
}

TEST(X3dScene, GeometryBoundTreeOptions) {
  const X3dScene s = load(kExamples / "GeometryBoundTreeOptions.x3d");
  ASSERT_EQ(s.shapes.size(), 3u);
  const X3dBoundType expected[] = {X3dBoundType::kObb, X3dBoundType::kAabb, X3dBoundType::kSphere};
  for (std::size_t i = 0; i < 3; ++i) {
    ASSERT_TRUE(s.shapes[i].bound_tree_options);
    EXPECT_EQ(s.shapes[i].bound_tree_options->bound_type, expected[i]);
    EXPECT_EQ(s.shapes[i].bound_tree_options->max_triangles_in_leaf, 1);
    EXPECT_FALSE(s.shapes[i].touchable);  // no surface
    EXPECT_EQ(s.shapes[i].mesh_W.triangles.size(), 12u);
  }
  ASSERT_TRUE(s.global_settings && s.global_settings->debug);
  EXPECT_EQ(s.global_settings->debug->draw_bound_tree, 1);
  // The first box is centred at its translation, whatever the rotation.
  EXPECT_TRUE(bounds(s.shapes[0].mesh_W).center().isApprox(Vec3(0.2, 0, 0), 1e-9));
}

TEST(X3dScene, HapticLayeredGroupGlobalOptions) {
  const X3dScene s = load(kExamples / "HapticLayeredGroup.x3d");
  ASSERT_TRUE(s.global_settings && s.global_settings->haptics);
  EXPECT_DOUBLE_EQ(s.global_settings->haptics->max_distance_m, 1.0);
  EXPECT_EQ(s.global_settings->haptics->touchable_face, X3dTouchableFace::kAsGraphics);
  ASSERT_EQ(s.shapes.size(), 2u);
  EXPECT_DOUBLE_EQ(s.shapes[0].surface.stiffness, 0.08);
  EXPECT_EQ(s.shapes[1].surface.kind, SurfaceKind::kFrictional);
  EXPECT_DOUBLE_EQ(s.shapes[1].surface.stiffness, 0.3);
}

TEST(X3dScene, SpringAndViscosityEffects) {
  const X3dScene spring = load(kExamples / "SpringEffect.x3d");
  ASSERT_EQ(spring.force_effects.springs.size(), 1u);
  const auto& k = spring.force_effects.springs[0];
  EXPECT_TRUE(k.position_m.isZero());
  EXPECT_DOUBLE_EQ(k.spring_constant_n_per_m, 100.0);
  EXPECT_DOUBLE_EQ(k.start_distance_m, 0.1);
  EXPECT_DOUBLE_EQ(k.escape_distance_m, 0.2);
  EXPECT_DOUBLE_EQ(k.damping_n_s_per_m, 0.0);
  ASSERT_EQ(spring.viewpoints.size(), 1u);
  EXPECT_TRUE(spring.viewpoints[0].position.isApprox(Vec3(0, 0, 0.6)));

  const X3dScene viscous = load(kExamples / "ViscosityEffect.x3d");
  ASSERT_EQ(viscous.force_effects.viscosities.size(), 1u);
  EXPECT_DOUBLE_EQ(viscous.force_effects.viscosities[0].viscosity_pa_s, 0.01);
  EXPECT_DOUBLE_EQ(viscous.force_effects.viscosities[0].radius_m, 0.0025);
  EXPECT_DOUBLE_EQ(viscous.force_effects.viscosities[0].damping_factor, 0.5);
}

TEST(X3dScene, FitToBoxTransformScalesTheSphereIntoTheBox) {
  const X3dScene s = load(kExamples / "FitToBoxTransform.x3d");
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_FALSE(s.shapes[0].touchable);
  EXPECT_TRUE(s.shapes[0].diffuse_color.isApprox(Vec3(0.3, 0.8, 0.8)));
  // Sphere r 0.15 (bound 0.3³) into boxSize 0.05 0.1 0.1 at 0.1 0.1 0, non-uniform.
  const auto b = bounds(s.shapes[0].mesh_W);
  EXPECT_NEAR(b.min().x(), 0.075, kTol);
  EXPECT_NEAR(b.max().x(), 0.125, kTol);
  EXPECT_NEAR(b.min().y(), 0.05, kTol);
  EXPECT_NEAR(b.max().y(), 0.15, kTol);
  EXPECT_NEAR(b.min().z(), -0.05, kTol);
  EXPECT_NEAR(b.max().z(), 0.05, kTol);
}

TEST(X3dScene, FitToBoxDefaultsAndUniformScaling) {
  const auto p = write_temp("fit.x3d", R"(<Scene>
  <FitToBoxTransform uniformScalingOnly='true'><Shape><Box size='2 4 8'/></Shape></FitToBoxTransform>
</Scene>)");
  const X3dScene s = load(p);
  ASSERT_EQ(s.shapes.size(), 1u);
  // boxSize .1 .1 .1, boxCenter 0 0 0 (constructor values); uniform: min(0.1/2, 0.1/4, 0.1/8).
  const auto b = bounds(s.shapes[0].mesh_W);
  EXPECT_TRUE(b.sizes().isApprox(Vec3(0.025, 0.05, 0.1), 1e-9));
  EXPECT_TRUE(b.center().isZero(1e-12));
}

TEST(X3dScene, DeformableShapeWithDeformer) {
  const X3dScene s = load(kExamples / "DeformableShape.x3d");
  ASSERT_EQ(s.shapes.size(), 1u);
  const auto& shape = s.shapes[0];
  EXPECT_TRUE(shape.deformable);
  EXPECT_EQ(shape.deformer_type, "CoordinateDeformer");
  EXPECT_TRUE(shape.touchable);
  EXPECT_EQ(shape.surface.kind, SurfaceKind::kSmooth);
  EXPECT_DOUBLE_EQ(shape.surface.stiffness, 0.1);
  EXPECT_TRUE(shape.diffuse_color.isApprox(Vec3(1, 0, 0)));
  EXPECT_FALSE(shape.solid);
  EXPECT_EQ(shape.geometry_type, "IndexedTriangleSet");
  EXPECT_EQ(shape.mesh_W.vertices.size(), 162u);
  EXPECT_EQ(shape.mesh_W.triangles.size(), 256u);
  EXPECT_EQ(shape.haptic_geometry_type, "Rectangle2D");
  EXPECT_EQ(shape.haptic_mesh_W.triangles.size(), 2u);
  // rotation 1 0 0 −1: the point (−0.05, 0.05, 0) goes to (−0.05, 0.05 cos 1, −0.05 sin 1).
  EXPECT_TRUE(shape.mesh_W.vertices[8].isApprox(Vec3(-0.05, 0.05 * std::cos(1.0), -0.05 * std::sin(1.0)), 1e-12));
  EXPECT_TRUE(contains(s.unsupported, "PythonScript (line 117)"));
}

TEST(X3dScene, FalconDeviceAndCalibration) {
  const X3dScene ex = load(kExamples / "FalconDevice.x3d");
  ASSERT_EQ(ex.devices.size(), 1u);
  EXPECT_EQ(ex.devices[0].type, "FalconDevice");
  EXPECT_EQ(ex.devices[0].device_name, "FALCON_1");
  ASSERT_TRUE(ex.devices[0].renderer);
  EXPECT_EQ(ex.devices[0].renderer->type, "GodObjectRenderer");
  EXPECT_EQ(ex.devices[0].renderer->kind, haptics::RendererKind::kGodObject);
  EXPECT_DOUBLE_EQ(ex.devices[0].force_limit_n, -1.0);

  // The stock settings file (no extension, a bare <DeviceInfo> root): diag(3, 3, 3, 1).
  const X3dScene settings = load(kH3d / "settings" / "common" / "device" / "FalconDevice");
  ASSERT_EQ(settings.devices.size(), 1u);
  const std::array<double, 16> expected{3, 0, 0, 0, 0, 3, 0, 0, 0, 0, 3, 0, 0, 0, 0, 1};
  EXPECT_EQ(settings.devices[0].position_calibration, expected);
  EXPECT_EQ(settings.devices[0].renderer->kind, haptics::RendererKind::kGodObject);
}

TEST(X3dScene, AnyDeviceRuspiniAndStylusNotAShape) {
  const X3dScene s = load(kExamples / "AnyDevice.x3d");
  ASSERT_EQ(s.devices.size(), 1u);
  EXPECT_EQ(s.devices[0].type, "AnyDevice");
  ASSERT_TRUE(s.devices[0].renderer);
  EXPECT_EQ(s.devices[0].renderer->kind, haptics::RendererKind::kRuspini);
  EXPECT_DOUBLE_EQ(s.devices[0].renderer->proxy_radius_m, 0.0025);
  EXPECT_TRUE(s.shapes.empty());
  EXPECT_TRUE(s.unsupported.empty());
  EXPECT_TRUE(s.warnings.empty());
}

TEST(X3dScene, PrototypeInstanceIsItsBodyWithTheFieldsSubstituted) {
  const X3dScene s = load(kExamples / "Prototype.x3d");
  // The instance is the body's Transform (translation = the instance's offset 0 0.08 0) and
  // its Shape, whose Text HoF does not draw.
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_FALSE(s.shapes[0].touchable);
  EXPECT_TRUE(contains(s.unsupported, "Text (line 26)")) << s.warnings.front();
  EXPECT_FALSE(contains(s.unsupported, "ProtoInstance"));
}

TEST(X3dScene, StylusSettingsGroupRoot) {
  const X3dScene s = load(kH3d / "settings" / "common" / "stylus" / "H3D Default.x3d");
  ASSERT_EQ(s.shapes.size(), 2u);
  EXPECT_FALSE(s.shapes[0].touchable);
  EXPECT_EQ(s.shapes[0].def, "");
  EXPECT_EQ(s.shapes[1].geometry_type, "Cylinder");
  // Cylinder (r 0.005, h 0.1) turned 90° about x: its axis lies along z, centred at z 0.08.
  const auto b = bounds(s.shapes[1].mesh_W);
  EXPECT_NEAR(b.min().z(), 0.03, 1e-6);
  EXPECT_NEAR(b.max().z(), 0.13, 1e-6);
  EXPECT_NEAR(b.max().y(), 0.005, 1e-6);
}

TEST(X3dScene, DefUseSharesTheNode) {
  const auto p = write_temp("defuse.x3d", R"(<?xml version='1.0'?>
<X3D><Scene>
  <!-- a comment -->
  <Transform translation='1 0 0'>
    <Shape DEF='S'>
      <Appearance><Material diffuseColor='0, 1, 0'/><SmoothSurface DEF='SURF' stiffness='0.7'/></Appearance>
      <Box DEF='B' size='0.2 0.2 0.2'/>
    </Shape>
  </Transform>
  <Transform translation='0 1 0'><Shape USE='S'/></Transform>
  <Shape>
    <Appearance><FrictionalSurface USE='SURF' containerField='surface'/></Appearance>
    <Box USE='B'/>
  </Shape>
</Scene></X3D>)");
  const X3dScene s = load(p);
  ASSERT_EQ(s.shapes.size(), 3u);
  EXPECT_EQ(s.shapes[0].def, "S");
  EXPECT_EQ(s.shapes[1].def, "S");
  EXPECT_TRUE(same(s.shapes[0].surface, s.shapes[1].surface));
  EXPECT_DOUBLE_EQ(s.shapes[1].surface.stiffness, 0.7);
  EXPECT_TRUE(s.shapes[1].diffuse_color.isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE(bounds(s.shapes[0].mesh_W).center().isApprox(Vec3(1, 0, 0)));
  EXPECT_TRUE(bounds(s.shapes[1].mesh_W).center().isApprox(Vec3(0, 1, 0)));
  // A USE element stands for the DEF'd node, whatever tag it is written with.
  EXPECT_EQ(s.shapes[2].surface_type, "SmoothSurface");
  EXPECT_TRUE(same(s.shapes[2].surface, s.shapes[0].surface));
  EXPECT_TRUE(bounds(s.shapes[2].mesh_W).sizes().isApprox(Vec3(0.2, 0.2, 0.2)));
  EXPECT_TRUE(s.unsupported.empty());
}

TEST(X3dScene, TransformRotationScaleCenter) {
  const auto p = write_temp("rot.x3d", R"(<Scene>
  <Transform translation='0 0 1' rotation='0 0 2 1.5707963267948966'>
    <Transform scale='2 2 2' center='1 0 0'>
      <Shape><IndexedTriangleSet index='0 1 2'><Coordinate point='1 0 0, 2 0 0, 1 1 0'/></IndexedTriangleSet></Shape>
    </Transform>
  </Transform>
  <Transform translation='0 0 5'><SpringEffect position='1 0 0'/><ForceField force='0 0 2'/></Transform>
</Scene>)");
  const X3dScene s = load(p);
  ASSERT_EQ(s.shapes.size(), 1u);
  const auto& v = s.shapes[0].mesh_W.vertices;
  // Inner: scale 2 about (1,0,0): (1,0,0)→(1,0,0), (2,0,0)→(3,0,0), (1,1,0)→(1,2,0).
  // Outer: 90° about z, then +z: (x,y,z)→(−y, x, z+1).
  EXPECT_TRUE(v[0].isApprox(Vec3(0, 1, 1), 1e-12));
  EXPECT_TRUE(v[1].isApprox(Vec3(0, 3, 1), 1e-12));
  EXPECT_TRUE(v[2].isApprox(Vec3(-2, 1, 1), 1e-12));
  ASSERT_EQ(s.force_effects.springs.size(), 1u);
  EXPECT_TRUE(s.force_effects.springs[0].position_m.isApprox(Vec3(1, 0, 5)));
  EXPECT_DOUBLE_EQ(s.force_effects.springs[0].spring_constant_n_per_m, 100.0);
  EXPECT_DOUBLE_EQ(s.force_effects.springs[0].start_distance_m, 0.01);
  ASSERT_EQ(s.force_effects.constants.size(), 1u);
  EXPECT_TRUE(s.force_effects.constants[0].force_n.isApprox(Vec3(0, 0, 2)));
}

TEST(X3dScene, IndexedFaceSetFanTriangulation) {
  const auto p = write_temp("ifs.x3d", R"(<Scene>
  <Shape>
    <Appearance><FrictionalSurface/></Appearance>
    <IndexedFaceSet coordIndex='0 1 2 3 -1 0 1 4 -1 0 1 2 3 4' ccw='false' solid='false'>
      <Coordinate point='0 0 0 1 0 0 1 1 0 0 1 0 0.5 0.5 1'/>
    </IndexedFaceSet>
  </Shape>
</Scene>)");
  const X3dScene s = load(p);
  ASSERT_EQ(s.shapes.size(), 1u);
  const auto& m = s.shapes[0].mesh_W;
  // quad → 2, triangle → 1, pentagon (no trailing −1) → 3.
  ASSERT_EQ(m.triangles.size(), 6u);
  // ccw='false': windings are flipped to counter-clockwise.
  EXPECT_EQ(m.triangles[0], (mesh::Tri{0, 2, 1}));
  EXPECT_EQ(m.triangles[1], (mesh::Tri{0, 3, 2}));
  EXPECT_FALSE(s.shapes[0].solid);
  EXPECT_EQ(s.shapes[0].surface.kind, SurfaceKind::kFrictional);
  EXPECT_DOUBLE_EQ(s.shapes[0].surface.dynamic_friction, 0.4);
}

TEST(X3dScene, UnsupportedNodesAreListedOnce) {
  const auto p = write_temp("unsup.x3d", R"(<X3D><head><meta name='x' content='y'/></head><Scene>
  <Inline url='"other.x3d"'/>
  <PythonScript DEF='PS' url='a.py'/>
  <ROUTE fromNode='A' fromField='b' toNode='C' toField='d'/>
  <Shape><Text string='"hi"'/></Shape>
  <GlobalSettings><HapticsOptions touchableFace='FRONT_AND_BACK' dynamicMode='ALWAYS' useBoundTree='false'/>
    <HapticsOptions touchableFace='BACK'/></GlobalSettings>
</Scene></X3D>)");
  const X3dScene s = load(p);
  EXPECT_TRUE(contains(s.warnings, ":2: Inline: none of its urls is a file beside the scene"));
  EXPECT_TRUE(contains(s.unsupported, "PythonScript 'PS' (line 3)"));
  EXPECT_TRUE(contains(s.unsupported, "ROUTE (line 4)"));
  EXPECT_TRUE(contains(s.unsupported, "Text (line 5)"));
  EXPECT_EQ(s.warnings.size(), 2u);  // the Inline not found, and the list
  ASSERT_EQ(s.shapes.size(), 1u);    // listed, not touchable, no geometry
  EXPECT_FALSE(s.shapes[0].touchable);
  ASSERT_TRUE(s.global_settings && s.global_settings->haptics);
  EXPECT_EQ(s.global_settings->haptics->touchable_face, X3dTouchableFace::kFrontAndBack);  // first wins
  EXPECT_EQ(s.global_settings->haptics->dynamic_mode, X3dDynamicMode::kAlways);
  EXPECT_FALSE(s.global_settings->haptics->use_bound_tree);
}

// ---- issue 35: grouping nodes, geometry, haptic nodes

// `text` fails to read, with `needle` in the message and the file named.
void expect_error_in(const std::string& name, const std::string& text, std::string_view needle) {
  const auto p = write_temp(name, text);
  const auto s = read_x3d_scene(p);
  ASSERT_FALSE(s.has_value()) << name;
  EXPECT_FALSE(s.error().file.empty()) << name;
  EXPECT_GT(s.error().line, 0) << name;
  EXPECT_NE(s.error().message.find(needle), std::string::npos) << name << ": " << s.error().to_string();
}

const std::string kTouch = "<Appearance><SmoothSurface/></Appearance>";

std::string scene(const std::string& body) { return "<X3D profile='H3DAPI'><Scene>\n" + body + "\n</Scene></X3D>\n"; }

std::vector<std::string> touchable_defs(const X3dScene& s) {
  std::vector<std::string> out;
  for (const auto& shape : s.shapes)
    if (shape.touchable && !shape.mesh_W.triangles.empty()) out.push_back(shape.def);
  return out;
}

// Signed volume enclosed by a closed triangle mesh: positive when its triangles face outward.
double signed_volume(const mesh::TriMesh& m) {
  double v = 0.0;
  for (const auto& t : m.triangles) v += m.vertices[t[0]].dot(m.vertices[t[1]].cross(m.vertices[t[2]])) / 6.0;
  return v;
}

Vec3 normal(const mesh::TriMesh& m, std::size_t i) {
  const auto& t = m.triangles[i];
  return (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).normalized();
}

TEST(X3dScene, GroupingNodesAreLookedInto) {
  const auto shape = [](const std::string& def) {
    return "<Shape DEF='" + def + "'>" + kTouch + "<Box size='0.1 0.1 0.1'/></Shape>";
  };
  const X3dScene s = load(write_temp(
      "groups.x3d", scene("<Switch whichChoice='1'>" + shape("SwitchA") + shape("SwitchB") +
                          "</Switch>"
                          "<Switch>" +
                          shape("SwitchNone") +
                          "</Switch>"
                          "<Switch whichChoice='5'>" +
                          shape("SwitchPast") +
                          "</Switch>"
                          "<LOD range='1'>" +
                          shape("LodNear") + shape("LodFar") +
                          "</LOD>"
                          "<Billboard>" +
                          shape("InBillboard") +
                          "</Billboard>"
                          "<Anchor url='\"x.html\"'>" +
                          shape("InAnchor") +
                          "</Anchor>"
                          "<Collision>" +
                          shape("InCollision") + "<Shape DEF='CollisionProxy' containerField='proxy'>" + kTouch +
                          "<Box/></Shape></Collision>"
                          "<StaticGroup>" +
                          shape("InStaticGroup") + "</StaticGroup>")));
  EXPECT_EQ(touchable_defs(s), (std::vector<std::string>{"SwitchB", "LodNear", "InBillboard", "InAnchor", "InCollision",
                                                         "InStaticGroup"}));
  EXPECT_FALSE(contains(s.unsupported, "Switch"));
  EXPECT_FALSE(contains(s.unsupported, "LOD"));
}

TEST(X3dScene, InlineIsReadBesideTheSceneFirstUrlFound) {
  const fs::path dir = fs::temp_directory_path() / "hof_x3d_inline_test";
  fs::create_directories(dir / "parts");
  std::ofstream(dir / "parts" / "ball.x3d") << scene("<Shape DEF='Ball'>" + kTouch + "<Sphere radius='0.02'/></Shape>");
  std::ofstream(dir / "main.x3d") << scene(
      "<Transform translation='0.1 0 0'><Inline url='\"missing.x3d\" \"http://example.org/a.x3d\" "
      "\"parts/ball.x3d\"'/></Transform>\n"
      "<Inline url='\"nowhere.x3d\"'/>");
  const X3dScene s = load(dir / "main.x3d");
  ASSERT_EQ(touchable_defs(s), std::vector<std::string>{"Ball"});
  EXPECT_NEAR(bounds(s.shapes[0].mesh_W).center().x(), 0.1, 1e-12);
  EXPECT_TRUE(contains(s.warnings, "main.x3d:3: Inline: none of its urls is a file beside the scene"));

  // A file that includes itself through another: an error naming the chain, at the Inline.
  std::ofstream(dir / "a.x3d") << scene("<Inline url='b.x3d'/>");
  std::ofstream(dir / "b.x3d") << scene("\n<Inline url='a.x3d'/>");
  const auto cycle = read_x3d_scene(dir / "a.x3d");
  ASSERT_FALSE(cycle);
  EXPECT_EQ(cycle.error().file, (dir / "b.x3d").string());
  EXPECT_EQ(cycle.error().line, 3);
  EXPECT_NE(cycle.error().message.find("a.x3d → b.x3d → a.x3d"), std::string::npos) << cycle.error().to_string();
}

TEST(X3dScene, ProtoInstanceFieldsAreSubstituted) {
  const X3dScene s = load(write_temp("proto.x3d", scene(R"(
<ProtoDeclare name='Block'>
  <ProtoInterface>
    <field name='offset' type='SFVec3f' accessType='inputOutput' value='0 0 0'/>
    <field name='k' type='SFFloat' accessType='inputOutput' value='0.3'/>
    <field name='look' type='SFNode' accessType='inputOutput'/>
  </ProtoInterface>
  <ProtoBody>
    <Transform><IS><connect nodeField='translation' protoField='offset'/></IS>
      <Shape DEF='Body'>
        <Appearance><IS><connect nodeField='material' protoField='look'/></IS>
          <SmoothSurface><IS><connect nodeField='stiffness' protoField='k'/></IS></SmoothSurface></Appearance>
        <Box size='0.02 0.02 0.02'/>
      </Shape>
    </Transform>
    <Group DEF='NotRendered'/>
  </ProtoBody>
</ProtoDeclare>
<ProtoInstance name='Block'/>
<ProtoInstance name='Block' DEF='Second'>
  <fieldValue name='offset' value='0.5 0 0'/>
  <fieldValue name='k' value='0.9'/>
  <fieldValue name='look'><Material diffuseColor='1 0 0'/></fieldValue>
</ProtoInstance>
<Transform translation='0 1 0'><ProtoInstance USE='Second'/></Transform>)")));
  ASSERT_EQ(s.shapes.size(), 3u);
  EXPECT_DOUBLE_EQ(s.shapes[0].surface.stiffness, 0.3);  // the interface's default
  EXPECT_DOUBLE_EQ(s.shapes[1].surface.stiffness, 0.9);  // the instance's value
  EXPECT_TRUE(s.shapes[1].diffuse_color.isApprox(Vec3(1, 0, 0)));
  EXPECT_NEAR(bounds(s.shapes[0].mesh_W).center().x(), 0.0, 1e-12);
  EXPECT_NEAR(bounds(s.shapes[1].mesh_W).center().x(), 0.5, 1e-12);
  EXPECT_NEAR(bounds(s.shapes[2].mesh_W).center().y(), 1.0, 1e-12);  // USE of the instance
  EXPECT_TRUE(s.unsupported.empty()) << s.unsupported.front();

  expect_error_in("recursive_proto.x3d", scene(R"(<ProtoDeclare name='R'><ProtoBody>
<Group><ProtoInstance name='R'/></Group></ProtoBody></ProtoDeclare>
<ProtoInstance name='R'/>)"),
                  "PROTOs instantiated more than 16 deep");
}

TEST(X3dScene, GeometryGroupIsOneTouchableGeometry) {
  // As H3D's GeometryGroup.x3d: a Box and an IndexedTriangleSet under one FrictionalSurface.
  const X3dScene s = load(write_temp("geometry_group.x3d", scene(R"(
<Shape><Appearance><Material/><FrictionalSurface/></Appearance>
  <GeometryGroup>
    <Box size='0.1 0.01 0.1'/>
    <IndexedTriangleSet index='0 1 2 0 2 3' solid='false'><Coordinate point='0 0 0 1 0 0 1 1 0 0 1 0'/></IndexedTriangleSet>
  </GeometryGroup>
</Shape>)")));
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_TRUE(s.shapes[0].touchable);
  EXPECT_EQ(s.shapes[0].mesh_W.triangles.size(), 12u + 2u);
  EXPECT_EQ(s.shapes[0].mesh_W.vertices.size(), 8u + 4u);
  EXPECT_FALSE(s.shapes[0].solid);  // a member is two-sided
  EXPECT_TRUE(s.unsupported.empty());
}

TEST(X3dScene, ElevationGridFollowsTheSpec) {
  const X3dScene s = load(
      write_temp("elevation.x3d", scene("<Shape>" + kTouch +
                                        "<ElevationGrid xDimension='3' zDimension='2' xSpacing='0.5' zSpacing='0.25' "
                                        "height='0 0.1 0.2 0.3 0.4 0.5'/></Shape>")));
  const mesh::TriMesh& m = s.shapes.at(0).mesh_W;
  ASSERT_EQ(m.vertices.size(), 6u);
  ASSERT_EQ(m.triangles.size(), 4u);                          // (3−1)(2−1) quads
  EXPECT_TRUE(m.vertices[5].isApprox(Vec3(1.0, 0.5, 0.25)));  // (i 2, j 1): height[2 + 1·3]
  for (std::size_t i = 0; i < m.triangles.size(); ++i) EXPECT_GT(normal(m, i).y(), 0.0) << i;  // ccw: +y
}

TEST(X3dScene, ExtrusionDefaultIsAClosedOutwardBox) {
  const X3dScene s = load(
      write_temp("extrusion.x3d",
                 scene("<Shape>" + kTouch +
                       "<Extrusion/></Shape>"
                       "<Shape>" +
                       kTouch + "<Extrusion ccw='false' beginCap='false' endCap='false' scale='0.5 0.5'/></Shape>")));
  // Default: the square ±1 swept along y from 0 to 1, capped: a 2 × 1 × 2 box.
  const mesh::TriMesh& box = s.shapes.at(0).mesh_W;
  EXPECT_EQ(box.triangles.size(), 8u + 2u + 2u);
  EXPECT_NEAR(signed_volume(box), 4.0, 1e-12);
  const auto b = bounds(box);
  EXPECT_TRUE(b.min().isApprox(Vec3(-1, 0, -1)));
  EXPECT_TRUE(b.max().isApprox(Vec3(1, 1, 1)));
  // No caps, scaled by half, turned inside out by ccw FALSE.
  const mesh::TriMesh& tube = s.shapes.at(1).mesh_W;
  EXPECT_EQ(tube.triangles.size(), 8u);
  EXPECT_NEAR(bounds(tube).max().x(), 0.5, 1e-12);
  const Vec3 side = normal(tube, 0);
  const auto& t = tube.triangles[0];
  const Vec3 centre = (tube.vertices[t[0]] + tube.vertices[t[1]] + tube.vertices[t[2]]) / 3.0;
  EXPECT_LT(side.dot(Vec3(centre.x(), 0, centre.z())), 0.0);  // faces the axis
}

TEST(X3dScene, ExtrusionAlongABentSpineKeepsItsSection) {
  // A unit square section swept along a right-angle bend: every ring stays a 0.2 square
  // perpendicular to the spine (the SCP of each point), and the tube has 3 segments.
  const X3dScene s = load(write_temp(
      "bent.x3d",
      scene("<Shape>" + kTouch +
            "<Extrusion crossSection='0.1 0.1 0.1 -0.1 -0.1 -0.1 -0.1 0.1 0.1 0.1' spine='0 0 0 0 1 0 1 1 0 2 1 0' "
            "beginCap='false' endCap='false'/></Shape>")));
  const mesh::TriMesh& m = s.shapes.at(0).mesh_W;
  ASSERT_EQ(m.vertices.size(), 4u * 5u);
  EXPECT_EQ(m.triangles.size(), 3u * 4u * 2u);
  // The last ring lies in the plane x = 2 (its spine direction is +x).
  for (std::size_t k = 15; k < 20; ++k) EXPECT_NEAR(m.vertices[k].x(), 2.0, 1e-12) << k;
  EXPECT_NEAR((m.vertices[15] - m.vertices[16]).norm(), 0.2, 1e-12);
}

TEST(X3dScene, TriangleAndQuadSetsFollowTheSpec) {
  const std::string square_strip = "<Coordinate point='0 0 0 1 0 0 0 1 0 1 1 0 0 2 0'/>";
  const X3dScene s = load(write_temp(
      "sets.x3d", scene("<Shape DEF='T'>" + kTouch +
                        "<TriangleSet><Coordinate point='0 0 0 1 0 0 0 1 0 5 5 5'/></TriangleSet></Shape>"
                        "<Shape DEF='F'>" +
                        kTouch +
                        "<TriangleFanSet fanCount='4 3'><Coordinate point='0 0 0 1 0 0 1 1 0 0 1 0 "
                        "2 0 0 3 0 0 3 1 0'/></TriangleFanSet></Shape>"
                        "<Shape DEF='S'>" +
                        kTouch + "<TriangleStripSet stripCount='5'>" + square_strip +
                        "</TriangleStripSet></Shape>"
                        "<Shape DEF='IT'>" +
                        kTouch + "<IndexedTriangleSet index='0 1 2'>" + square_strip +
                        "</IndexedTriangleSet></Shape>"
                        "<Shape DEF='IF'>" +
                        kTouch + "<IndexedTriangleFanSet index='0 1 3 2 -1 2 3 4'>" + square_strip +
                        "</IndexedTriangleFanSet></Shape>"
                        "<Shape DEF='IS'>" +
                        kTouch + "<IndexedTriangleStripSet index='0 1 2 3 -1 2 3 4'>" + square_strip +
                        "</IndexedTriangleStripSet></Shape>"
                        "<Shape DEF='Q'>" +
                        kTouch +
                        "<QuadSet><Coordinate point='0 0 0 1 0 0 1 1 0 0 1 0'/></QuadSet></Shape>"
                        "<Shape DEF='IQ'>" +
                        kTouch + "<IndexedQuadSet index='0 1 3 2'>" + square_strip + "</IndexedQuadSet></Shape>")));
  const std::vector<std::size_t> expected{1, 2 + 1, 3, 1, 2 + 1, 2 + 1, 2, 2};
  ASSERT_EQ(s.shapes.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    const mesh::TriMesh& m = s.shapes[i].mesh_W;
    EXPECT_EQ(m.triangles.size(), expected[i]) << s.shapes[i].def;
    // Every triangle of these planar, counter-clockwise sets faces +z (strips alternate
    // their vertex order so that they all do).
    for (std::size_t k = 0; k < m.triangles.size(); ++k)
      EXPECT_GT(normal(m, k).z(), 0.99) << s.shapes[i].def << " " << k;
  }
  EXPECT_TRUE(contains(s.warnings, "TriangleSet: 1 points left over (not a whole triangle): ignored"));
}

TEST(X3dScene, Disk2DAndRectangle2DAreTwoSidedPlanes) {
  const X3dScene s = load(write_temp("planar.x3d", scene("<Shape>" + kTouch +
                                                         "<Disk2D innerRadius='0.5' outerRadius='1'/></Shape>"
                                                         "<Shape>" +
                                                         kTouch +
                                                         "<Disk2D outerRadius='0.2'/></Shape>"
                                                         "<Shape>" +
                                                         kTouch + "<Rectangle2D size='0.2 0.1'/></Shape>")));
  ASSERT_EQ(s.shapes.size(), 3u);
  for (const auto& shape : s.shapes) {
    EXPECT_FALSE(shape.solid);  // 19775-1: Geometry2D nodes default to solid FALSE
    for (std::size_t k = 0; k < shape.mesh_W.triangles.size(); ++k) EXPECT_GT(normal(shape.mesh_W, k).z(), 0.99);
  }
  const auto ring = bounds(s.shapes[0].mesh_W);
  EXPECT_NEAR(ring.max().x(), 1.0, 1e-12);
  double area = 0.0;
  for (std::size_t k = 0; k < s.shapes[0].mesh_W.triangles.size(); ++k) {
    const auto& t = s.shapes[0].mesh_W.triangles[k];
    const auto& v = s.shapes[0].mesh_W.vertices;
    area += 0.5 * (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]).norm();
  }
  EXPECT_NEAR(area, 0.75 * std::numbers::pi, 0.02);  // π (1 − 0.25), tessellated
  EXPECT_EQ(s.shapes[1].mesh_W.triangles.size(), 32u);
  EXPECT_NEAR(bounds(s.shapes[2].mesh_W).sizes().x(), 0.2, 1e-12);
}

TEST(X3dScene, HapticNodesOfTheExamples) {
  const X3dScene s = load(write_temp("haptic_nodes.x3d", scene(R"(
<Shape><Rectangle2D size='0.2 0.1'/>
  <Appearance><MultiDeviceSurface><SmoothSurface stiffness='0.7'/><FrictionalSurface/></MultiDeviceSurface></Appearance></Shape>
<Shape><Appearance><Material/></Appearance><Box size='0.1 0.1 0.1' DEF='B'/></Shape>
<Transform translation='1 0 0'>
  <MagneticGeometryEffect startDistance='0.03' escapeDistance='0.04' springConstant='300'><Box USE='B'/></MagneticGeometryEffect>
</Transform>
<PositionFunctionEffect>
  <GeneralFunction containerField='xFunction' function='10*y' params='x,y,z'/>
  <GeneralFunction containerField='yFunction' function='0' params='x,y,z'/>
  <GeneralFunction containerField='zFunction' function='-2*x^2' params='x,y,z'/>
</PositionFunctionEffect>
<TimeFunctionEffect>
  <GeneralFunction containerField='xFunction' function='sin(2*t)' params='t'/>
  <GeneralFunction containerField='yFunction' function='cos(2*t)' params='t'/>
  <GeneralFunction containerField='zFunction' function='0' params='t'/>
</TimeFunctionEffect>
<RotationalSpringEffect desiredAxis='0 1 0' springConstant='100'/>)")));
  // MultiDeviceSurface: device 0, the only one HoF drives, feels the first surface.
  ASSERT_TRUE(s.shapes.at(0).touchable);
  EXPECT_EQ(s.shapes[0].surface_type, "SmoothSurface");
  EXPECT_DOUBLE_EQ(s.shapes[0].surface.stiffness, 0.7);
  haptics::ForceEffects effects = s.force_effects;
  ASSERT_EQ(effects.magnets.size(), 1u);
  EXPECT_EQ(effects.magnets[0].surface->triangles.size(), 12u);
  EXPECT_NEAR(bounds(*effects.magnets[0].surface).center().x(), 1.0, 1e-12);  // under its Transform
  ASSERT_EQ(effects.position_functions.size(), 1u);
  ASSERT_EQ(effects.time_functions.size(), 1u);
  EXPECT_TRUE(contains(s.unsupported, "RotationalSpringEffect (a torque: HoF renders forces only)"));

  // Only the position function: F = (10 y, 0, −2 x²).
  haptics::ForceEffects position;
  position.position_functions = effects.position_functions;
  EXPECT_TRUE(position.evaluate(Vec3(0.5, 0.2, 0), Vec3::Zero()).isApprox(Vec3(2.0, 0.0, -0.5)));
  haptics::ForceEffects time;
  time.time_functions = effects.time_functions;
  EXPECT_TRUE(time.evaluate(Vec3::Zero(), Vec3::Zero(), 0.25).isApprox(Vec3(std::sin(0.5), std::cos(0.5), 0.0)));
  // The magnet: 0.02 m off the box's +x face it catches (≤ 0.03) and pulls with k·d.
  haptics::ForceEffects magnet;
  magnet.magnets = effects.magnets;
  EXPECT_TRUE(magnet.evaluate(Vec3(1.07, 0, 0), Vec3::Zero()).isApprox(Vec3(-300 * 0.02, 0, 0)));
  EXPECT_TRUE(magnet.evaluate(Vec3(1.085, 0, 0), Vec3::Zero()).isApprox(Vec3(-300 * 0.035, 0, 0)));  // held till 0.04
  EXPECT_TRUE(magnet.evaluate(Vec3(1.1, 0, 0), Vec3::Zero()).isZero());                              // escaped
  EXPECT_TRUE(magnet.evaluate(Vec3(1.085, 0, 0), Vec3::Zero()).isZero());  // not caught again until 0.03
}

TEST(X3dScene, DebugOptionsSceneHasATouchableExtrusion) {
  // H3D's DebugOptions.x3d: its shape is an Extrusion under a FrictionalSurface.
  const X3dScene s = load(write_temp("debug_options.x3d", scene(R"(
<GlobalSettings><DebugOptions drawBound='true' drawHapticTriangles='true'/><HapticsOptions maxDistance='-1'/></GlobalSettings>
<Shape>
  <Extrusion beginCap='true' endCap='false' solid='false'
    crossSection='0.0707 0 0.05 -0.05 0 -0.0707 -0.05 -0.05 -0.0707 0 -0.05 0.05 0 0.0707 0.05 0.05 0.0707 0'
    scale='1 1 0.5 0.5 0.2 0.2' spine='0 0 0 0 0.1 0 0 0.35 0'/>
  <Appearance><Material diffuseColor='0.6 1 1'/><FrictionalSurface/></Appearance>
</Shape>)")));
  ASSERT_EQ(s.shapes.size(), 1u);
  EXPECT_TRUE(s.shapes[0].touchable);
  EXPECT_EQ(s.shapes[0].geometry_type, "Extrusion");
  EXPECT_EQ(s.shapes[0].mesh_W.triangles.size(), 2u * 8u * 2u + 6u);  // 2 segments × 8 edges, a begin cap of 8 points
  ASSERT_TRUE(s.global_settings && s.global_settings->debug);
}

TEST(X3dScene, CoordinatesAnimatedByACoordinateInterpolatorAreDrawnAtTheFirstKey) {
  // As H3D's CoordinateInterpolator.x3d: the Coordinate has no points of its own.
  const X3dScene s = load(write_temp("coordinate_interpolator.x3d", scene(R"(
<Shape><Appearance><Material/></Appearance>
  <IndexedTriangleSet index='0 1 2 0 2 1'><Coordinate DEF='C'/></IndexedTriangleSet></Shape>
<TimeSensor DEF='T' cycleInterval='4' loop='true'/>
<CoordinateInterpolator DEF='I' key='0 1' keyValue='0 0 0 1 0 0 0 1 0  0 0 0 2 0 0 0 2 0'/>
<ROUTE fromNode='T' fromField='fraction_changed' toNode='I' toField='set_fraction'/>
<ROUTE fromNode='I' fromField='value_changed' toNode='C' toField='point'/>)")));
  ASSERT_EQ(s.shapes.size(), 1u);
  ASSERT_EQ(s.shapes[0].mesh_W.vertices.size(), 3u);
  EXPECT_TRUE(s.shapes[0].mesh_W.vertices[1].isApprox(Vec3(1, 0, 0)));
  EXPECT_TRUE(contains(s.warnings,
                       "Coordinate 'C' has no points: a ROUTE (line 8) animates it from CoordinateInterpolator 'I'"));
}

TEST(X3dScene, ClassicEncodingIsNotRead) {
  expect_error_in("classic.x3d", "#X3D V3.0 utf8\nPROFILE Immersive\nShape { geometry Box {} }\n",
                  "the X3D classic VRML encoding");
}

void expect_error(const std::string& name, const std::string& text, std::int64_t line, std::string_view needle) {
  const auto p = write_temp(name, text);
  const auto s = read_x3d_scene(p);
  ASSERT_FALSE(s.has_value()) << name;
  EXPECT_EQ(s.error().file, p.string()) << name;
  EXPECT_EQ(s.error().line, line) << name << ": " << s.error().to_string();
  EXPECT_NE(s.error().message.find(needle), std::string::npos) << name << ": " << s.error().to_string();
}

TEST(X3dScene, ErrorsCarryFileAndLine) {
  expect_error("malformed.x3d", "<Scene>\n  <Shape>\n  <Box/>\n</Scene>\n", 4, "malformed XML");
  expect_error("range.x3d", R"(<Scene>
  <Shape>
    <IndexedTriangleSet index='0 1 3'>
      <Coordinate point='0 0 0 1 0 0 0 1 0'/>
    </IndexedTriangleSet>
  </Shape>
</Scene>)",
               3, "index 3 out of range");
  expect_error("range_ifs.x3d",
               "<Scene>\n<Shape><IndexedFaceSet coordIndex='0 1 -2'>"
               "<Coordinate point='0 0 0 1 0 0 0 1 0'/></IndexedFaceSet></Shape></Scene>",
               2, "out of range");
  expect_error("nan.x3d", "<Scene>\n\n<Transform translation='1 x 0'/>\n</Scene>", 3, "'x' is not a number");
  expect_error("surface.x3d",
               "<Scene><Shape>\n<Appearance><SmoothSurface stiffness='stiff'/></Appearance></Shape></Scene>", 2,
               "stiffness");
  expect_error("use.x3d", "<Scene>\n<Shape>\n<Box USE='NOPE'/>\n</Shape></Scene>", 3, "USE='NOPE'");
  expect_error("use_before_def.x3d", "<Scene>\n<Shape USE='S'/>\n<Shape DEF='S'/></Scene>", 2, "USE='S'");
  expect_error("enum.x3d", "<Scene><GlobalSettings>\n<HapticsOptions touchableFace='SIDE'/></GlobalSettings></Scene>",
               2, "touchableFace");
  // Found by fuzz_x3d (the anchor DeformableShape.x3d with an index of 1.33e125): converting
  // an integer-valued number past 2⁶³ was undefined behaviour; now a clear error.
  expect_error("huge_index.x3d", R"(<Scene>
  <Shape>
    <IndexedTriangleSet index='0 1 1.33e125'>
      <Coordinate point='0 0 0 1 0 0 0 1 0'/>
    </IndexedTriangleSet>
  </Shape>
</Scene>)",
               3, "1.33e+125 is out of range");
  const auto missing = read_x3d_scene("/nonexistent/none.x3d");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
}

}  // namespace
}  // namespace hof::scene
