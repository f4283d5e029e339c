// X3D (H3D API) scene reader: every anchor scene from H3D's examples and settings loads; the
// haptic content of each (surfaces, options, effects, devices, FitToBox, DeformableShape) is
// what the files say; DEF/USE, transforms and face sets on small inline scenes; malformed
// scenes fail with the file and line.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

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
  const X3dScene s = load(kExamples / "Surfaces.x3d");
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

  // OpenHapticsSurface derives from MagneticSurface: all defaults.
  EXPECT_EQ(s.shapes[3].surface_type, "OpenHapticsSurface");
  EXPECT_EQ(s.shapes[3].surface.kind, SurfaceKind::kMagnetic);
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

  EXPECT_TRUE(contains(s.unsupported, "ExternProtoDeclare"));
  EXPECT_TRUE(contains(s.unsupported, "ProtoInstance"));
  EXPECT_TRUE(contains(s.unsupported, "ImageTexture 'I' (line"));
  EXPECT_EQ(s.warnings.size(), 1u);
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

TEST(X3dScene, PrototypeIsListedAsUnsupported) {
  const X3dScene s = load(kExamples / "Prototype.x3d");
  EXPECT_TRUE(s.shapes.empty());
  EXPECT_TRUE(contains(s.unsupported, "ProtoDeclare (line 11)"));
  EXPECT_TRUE(contains(s.unsupported, "ProtoInstance (line 37)"));
  EXPECT_EQ(s.warnings.size(), 1u);
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
  EXPECT_TRUE(contains(s.unsupported, "Inline url=\"other.x3d\" (line 2)"));
  EXPECT_TRUE(contains(s.unsupported, "PythonScript 'PS' (line 3)"));
  EXPECT_TRUE(contains(s.unsupported, "ROUTE (line 4)"));
  EXPECT_TRUE(contains(s.unsupported, "Text (line 5)"));
  EXPECT_EQ(s.warnings.size(), 1u);
  ASSERT_EQ(s.shapes.size(), 1u);  // listed, not touchable, no geometry
  EXPECT_FALSE(s.shapes[0].touchable);
  ASSERT_TRUE(s.global_settings && s.global_settings->haptics);
  EXPECT_EQ(s.global_settings->haptics->touchable_face, X3dTouchableFace::kFrontAndBack);  // first wins
  EXPECT_EQ(s.global_settings->haptics->dynamic_mode, X3dDynamicMode::kAlways);
  EXPECT_FALSE(s.global_settings->haptics->use_bound_tree);
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
</Scene>)", 3, "index 3 out of range");
  expect_error("range_ifs.x3d", "<Scene>\n<Shape><IndexedFaceSet coordIndex='0 1 -2'>"
               "<Coordinate point='0 0 0 1 0 0 0 1 0'/></IndexedFaceSet></Shape></Scene>", 2, "out of range");
  expect_error("nan.x3d", "<Scene>\n\n<Transform translation='1 x 0'/>\n</Scene>", 3, "'x' is not a number");
  expect_error("surface.x3d", "<Scene><Shape>\n<Appearance><SmoothSurface stiffness='stiff'/></Appearance></Shape></Scene>", 2,
               "stiffness");
  expect_error("use.x3d", "<Scene>\n<Shape>\n<Box USE='NOPE'/>\n</Shape></Scene>", 3, "USE='NOPE'");
  expect_error("use_before_def.x3d", "<Scene>\n<Shape USE='S'/>\n<Shape DEF='S'/></Scene>", 2, "USE='S'");
  expect_error("enum.x3d", "<Scene><GlobalSettings>\n<HapticsOptions touchableFace='SIDE'/></GlobalSettings></Scene>", 2,
               "touchableFace");
  // Found by fuzz_x3d (the anchor DeformableShape.x3d with an index of 1.33e125): converting
  // an integer-valued number past 2⁶³ was undefined behaviour; now a clear error.
  expect_error("huge_index.x3d", R"(<Scene>
  <Shape>
    <IndexedTriangleSet index='0 1 1.33e125'>
      <Coordinate point='0 0 0 1 0 0 0 1 0'/>
    </IndexedTriangleSet>
  </Shape>
</Scene>)", 3, "1.33e+125 is out of range");
  const auto missing = read_x3d_scene("/nonexistent/none.x3d");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
}

}  // namespace
}  // namespace hof::scene
