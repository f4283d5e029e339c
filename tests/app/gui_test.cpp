// `hof gui` under Xvfb: the bundled liver project is drawn, pressed with the mouse stylus,
// tuned and saved through the window's script — the path a user (and the docs' screenshots)
// take. The checks read the PNGs the window wrote and the project it saved.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "hof/app/gui/gui_script.h"
#include "hof/haptics/device_backends/replay_device.h"
#include "hof/render/image.h"
#include "hof/scene/project.h"
#include "hof/scene/world.h"

namespace {

namespace fs = std::filesystem;
using hof::app::ScriptAction;

const fs::path kLiverProject = fs::path(HOF_SOURCE_DIR) / "examples/liver-palpation-medium-fem.hof";
constexpr int kPanelWidth = 390;  // the left panel; the 3D view is to its right

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hof-gui-test-" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct GuiRun {
  int status{-1};
  std::string output;
};

/// Runs `hof gui PROJECT --script SCRIPT` in a virtual X server (no project: an empty window).
GuiRun run_gui(const fs::path& dir, const std::string& script, const fs::path& project = kLiverProject) {
  const fs::path script_file = dir / "actions.txt";
  std::ofstream(script_file) << script;
  const fs::path log = dir / "output.txt";
  const std::string file = project.empty() ? std::string() : " '" + project.string() + "'";
  const std::string command = "xvfb-run -a -s '-screen 0 1280x720x24' '" + std::string(HOF_BIN) + "' gui" + file +
                              " --size 1280x720 --script '" + script_file.string() + "' > '" + log.string() + "' 2>&1";
  GuiRun r;
  r.status = std::system(command.c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  r.output = text.str();
  return r;
}

bool is_tissue(const std::uint8_t* p) {
  // The thesis' liver material (diffuse 0.36 0.11 0.04) lit: red well above green and blue.
  return p[0] > 40 && p[0] > 2 * p[1] && p[0] > 2 * p[2];
}

struct Coverage {
  double share{0.0};  // of the 3D view
  double cx{0.0}, cy{0.0};
};

Coverage tissue_coverage(const hof::render::Image& image) {
  Coverage c;
  std::size_t count = 0, view = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = kPanelWidth; x < image.width; ++x) {
      ++view;
      if (is_tissue(&image.rgb[3 * (static_cast<std::size_t>(y) * image.width + x)])) {
        ++count;
        c.cx += x;
        c.cy += y;
      }
    }
  }
  if (count) {
    c.cx /= static_cast<double>(count);
    c.cy /= static_cast<double>(count);
  }
  c.share = view ? static_cast<double>(count) / static_cast<double>(view) : 0.0;
  return c;
}

double mean_difference(const hof::render::Image& a, const hof::render::Image& b, int cx, int cy, int half) {
  double sum = 0.0;
  std::size_t n = 0;
  for (int y = std::max(cy - half, 0); y < std::min(cy + half, a.height); ++y) {
    for (int x = std::max(cx - half, kPanelWidth); x < std::min(cx + half, a.width); ++x) {
      for (int k = 0; k < 3; ++k) {
        const std::size_t i = 3 * (static_cast<std::size_t>(y) * a.width + x) + k;
        sum += std::abs(static_cast<int>(a.rgb[i]) - static_cast<int>(b.rgb[i]));
        ++n;
      }
    }
  }
  return n ? sum / static_cast<double>(n) : 0.0;
}

double number_after(const std::string& text, const std::string& pattern) {
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(pattern + " ([0-9.]+)"))) return -1.0;
  return std::stod(m[1]);
}

TEST(GuiScript, ReadsEveryActionAndNamesTheLineOfAnError) {
  auto ok = hof::app::parse_script(
      "# a demo\nwait 0.5\nanimate off\nstep 3\nset haptics/surface@stiffness 0.4\nset graphics@viewpoint 0 -0.4 0.2\n"
      "mouse 640 360 0.01\nscreenshot a.png\nsave b.hof\nreset\nquit\n",
      "demo.txt");
  ASSERT_TRUE(ok) << ok.error().to_string();
  ASSERT_EQ(ok->size(), 10u);
  EXPECT_EQ((*ok)[0].kind, ScriptAction::Kind::kWait);
  EXPECT_DOUBLE_EQ((*ok)[0].number, 0.5);
  EXPECT_FALSE((*ok)[1].on);
  EXPECT_DOUBLE_EQ((*ok)[2].number, 3.0);
  EXPECT_EQ((*ok)[3].element, "haptics/surface");
  EXPECT_EQ((*ok)[3].attribute, "stiffness");
  EXPECT_EQ((*ok)[3].value, "0.4");
  EXPECT_EQ((*ok)[4].value, "0 -0.4 0.2");
  EXPECT_DOUBLE_EQ((*ok)[5].depth, 0.01);
  EXPECT_EQ((*ok)[6].file, "a.png");
  EXPECT_EQ((*ok)[7].line, 9);

  auto edits = hof::app::parse_script(
      "replace mechanics/Liver/FEM TetrahedronHyperelasticityFEMForceField materialName=NeoHookean \"ParameterSet=1 "
      "2\"\n"
      "add mechanics/Liver FixedProjectiveConstraint pin indices=\"1 2\"\nremove mechanics/Liver/pin\n"
      "region Liver box 0 0 0 0.1 0.1 0.1 9000\nregion clear\n",
      "edits.txt");
  ASSERT_TRUE(edits) << edits.error().to_string();
  ASSERT_EQ(edits->size(), 5u);
  EXPECT_EQ((*edits)[0].kind, ScriptAction::Kind::kEdit);
  EXPECT_EQ((*edits)[0].type, "TetrahedronHyperelasticityFEMForceField");
  ASSERT_EQ((*edits)[0].attributes.size(), 2u);
  EXPECT_EQ((*edits)[0].attributes[1], (std::pair<std::string, std::string>{"ParameterSet", "1 2"}));
  EXPECT_EQ((*edits)[1].name, "pin");
  EXPECT_EQ((*edits)[1].attributes[0].second, "1 2");
  EXPECT_EQ((*edits)[2].value, "remove");
  EXPECT_TRUE((*edits)[3].box);
  EXPECT_EQ((*edits)[3].numbers.size(), 7u);
  EXPECT_TRUE((*edits)[4].numbers.empty());

  for (const char* bad : {"wait\n",
                          "wait -1\n",
                          "animate maybe\n",
                          "set stiffness 0.4\n",
                          "mouse 1\n",
                          "screenshot a.jpg\n",
                          "save a.scn\n",
                          "frobnicate\n",
                          "step 0\n",
                          "record a.txt\n",
                          "record\n",
                          "show toolbar\n",
                          "replace mechanics/Liver TetrahedronFEMForceField\n",
                          "add mechanics/Liver/FEM X y\n",
                          "remove haptics/x\n",
                          "replace mechanics/Liver/FEM T youngModulus\n",
                          "region Liver sphere 0 0 0 1\n",
                          "region Liver cube 0 0 0 1 2\n",
                          "tool\n",
                          "tool capsule 0.08\n",
                          "tool sphere -0.01\n",
                          "tool cube 1\n",
                          "tool mesh\n",
                          "rotate 0 0 0 30\n",
                          "rotate 1 0 0\n",
                          "contacts maybe\n",
                          "pair Liver off\n",
                          "pair Liver Stomach sometimes\n"}) {
    auto e = hof::app::parse_script(std::string("wait 0\n") + bad, "s.txt");
    ASSERT_FALSE(e) << bad;
    EXPECT_EQ(e.error().line, 2) << bad;
    EXPECT_EQ(e.error().file, "s.txt");
  }
}

TEST(GuiWindow, DrawsTheLiverAndTheMouseStylusPressesItVisibly) {
  const fs::path dir = scratch("press");
  // 1. Where is the organ? (the view is the project's; find the liver's pixels)
  const GuiRun first = run_gui(dir, "wait 1\nscreenshot " + (dir / "before.png").string() + "\nquit\n");
  ASSERT_EQ(first.status, 0) << first.output;
  auto before = hof::render::read_png(dir / "before.png");
  ASSERT_TRUE(before) << before.error().to_string();
  ASSERT_EQ(before->width, 1280);
  const Coverage organ = tissue_coverage(*before);
  EXPECT_GT(organ.share, 0.04) << "the liver covers too little of the view";
  EXPECT_LT(organ.share, 0.7) << "the liver fills the view: the camera is inside or too close";
  // 2. Press it with the mouse stylus 12 mm deep at its centre.
  const int x = static_cast<int>(organ.cx), y = static_cast<int>(organ.cy);
  const GuiRun press = run_gui(dir, "wait 1\nscreenshot " + (dir / "rest.png").string() + "\nmouse " +
                                        std::to_string(x) + " " + std::to_string(y) + " 0.012\nwait 2.5\nscreenshot " +
                                        (dir / "pressed.png").string() + "\nquit\n");
  ASSERT_EQ(press.status, 0) << press.output;
  auto rest = hof::render::read_png(dir / "rest.png");
  auto pressed = hof::render::read_png(dir / "pressed.png");
  ASSERT_TRUE(rest && pressed);
  EXPECT_GT(tissue_coverage(*pressed).share, 0.5 * organ.share) << "the liver is no longer drawn";
  // The picture changes where the organ is pressed (the stylus, the dent), and much less far from it.
  const double near = mean_difference(*rest, *pressed, x, y, 40);
  const double far = mean_difference(*rest, *pressed, 1280 - 60, 720 - 60, 40);
  EXPECT_GT(near, 4.0) << press.output;
  EXPECT_GT(near, 4.0 * far + 1.0);
  // Contact, force and deformation, as the window measured them.
  EXPECT_GT(number_after(press.output, "contact"), 0.2) << press.output;
  EXPECT_GT(number_after(press.output, "max force"), 0.05) << press.output;
  EXPECT_GT(number_after(press.output, "max surface displacement"), 1.0) << press.output;
  EXPECT_LT(number_after(press.output, "max force"), 8.0 + 1e-9) << "above the device's force limit";
}

TEST(GuiWindow, TheNeedleIsMountedTunedInsertedThroughTheCapsuleAndSaved) {
  const fs::path dir = scratch("needle");
  // Where the organ is (the project's view).
  const GuiRun first = run_gui(dir, "wait 1\nscreenshot " + (dir / "before.png").string() + "\nquit\n");
  ASSERT_EQ(first.status, 0) << first.output;
  auto before = hof::render::read_png(dir / "before.png");
  ASSERT_TRUE(before);
  const Coverage organ = tissue_coverage(*before);
  const fs::path saved = dir / "needle.hof";
  // Mount the needle, make the capsule 8 mm deep and the model Simone-Okamura, then push the
  // mouse stylus 25 mm into the liver at its centre, and out again.
  const std::string at = std::to_string(static_cast<int>(organ.cx)) + " " + std::to_string(static_cast<int>(organ.cy));
  const GuiRun run = run_gui(dir,
                             "needle on\nset haptics/needle/tissue@capsule 0.008\n"
                             "set haptics/needle/tissue@model simone-okamura\nwait 0.5\nmouse " +
                                 at +
                                 " -0.01\nwait 0.5\n"
                                 "mouse " +
                                 at + " 0.025\nwait 2\nscreenshot " + (dir / "inserted.png").string() +
                                 "\n"
                                 "mouse " +
                                 at + " -0.03\nwait 2\nsave " + saved.string() + "\nquit\n");
  ASSERT_EQ(run.status, 0) << run.output;
  // The window logged the insertion's events.
  EXPECT_NE(run.output.find("the needle is mounted"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("needle: touching Liver"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("needle: the capsule of Liver broke at"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("needle: withdrawn"), std::string::npos) << run.output;
  EXPECT_LT(number_after(run.output, "max force"), 8.0 + 1e-9) << "above the device's force limit";
  auto inserted = hof::render::read_png(dir / "inserted.png");
  ASSERT_TRUE(inserted);
  EXPECT_GT(tissue_coverage(*inserted).share, 0.5 * organ.share) << "the liver is no longer drawn";
  // The saved project mounts the needle with the settings made in the window.
  auto reloaded = hof::scene::read_project(saved);
  ASSERT_TRUE(reloaded) << reloaded.error().to_string();
  ASSERT_TRUE(reloaded->needle);
  EXPECT_EQ(reloaded->needle->tissue.capsule_m, 0.008);
  EXPECT_EQ(reloaded->needle->tissue.model, hof::procedures::NeedleForceModel::kSimoneOkamura);
}

TEST(GuiWindow, ScriptChangesSettingsAndTheSavedProjectReloadsToExactlyThem) {
  const fs::path dir = scratch("save");
  const fs::path saved = dir / "tuned.hof";
  const GuiRun run = run_gui(dir,
                             "set haptics/surface@stiffness 0.4\nset haptics@renderer GodObjectRenderer\n"
                             "set mechanics/Liver/FEM@youngModulus 8000\nwait 0.3\nsave " +
                                 saved.string() + "\nquit\n");
  ASSERT_EQ(run.status, 0) << run.output;
  auto original = hof::scene::read_project(kLiverProject);
  auto reloaded = hof::scene::read_project(saved);
  ASSERT_TRUE(original && reloaded) << (reloaded ? "" : reloaded.error().to_string());
  EXPECT_DOUBLE_EQ(reloaded->surface.stiffness, 0.4);
  EXPECT_EQ(reloaded->renderer, hof::haptics::RendererKind::kGodObject);
  ASSERT_EQ(reloaded->parameters.size(), 1u);
  EXPECT_EQ(reloaded->parameters[0].body, "Liver");
  EXPECT_EQ(reloaded->parameters[0].component, "FEM");
  EXPECT_EQ(reloaded->parameters[0].parameter, "youngModulus");
  EXPECT_DOUBLE_EQ(reloaded->parameters[0].value, 8000.0);
  // The scene is the same file, referred to from where the project now is.
  EXPECT_EQ(fs::canonical(hof::scene::scene_file(*reloaded, saved)),
            fs::canonical(hof::scene::scene_file(*original, kLiverProject)));
  // Everything else is as it was.
  hof::scene::HofProject expected = *original;
  expected.surface.stiffness = 0.4;
  expected.renderer = hof::haptics::RendererKind::kGodObject;
  expected.parameters = reloaded->parameters;
  expected.mechanics_scene = reloaded->mechanics_scene;
  EXPECT_EQ(hof::scene::to_xml(*reloaded), hof::scene::to_xml(expected));
}

TEST(GuiWindow, TheSceneTreeSwitchesTheForceFieldAddsARegionColoursByStressAndSavesTheScene) {
  const fs::path dir = scratch("structure");
  const fs::path saved = dir / "edited.hof";
  const GuiRun first = run_gui(dir, "wait 0.5\nscreenshot " + (dir / "view.png").string() + "\nquit\n");
  ASSERT_EQ(first.status, 0) << first.output;
  auto view = hof::render::read_png(dir / "view.png");
  ASSERT_TRUE(view);
  const Coverage organ = tissue_coverage(*view);
  // Neo-Hookean with the liver's E = 5.4 kPa, ν = 0.45 (SOFA's ParameterSet μ k), a stiff
  // sphere in it, then a press with the colours by von Mises stress.
  const GuiRun run = run_gui(
      dir,
      "set mechanics/Liver/FEM@youngModulus 8000\nwait 0.2\nset mechanics/Liver/solver@rayleighMass 0.3\n"
      "replace mechanics/Liver/FEM TetrahedronHyperelasticityFEMForceField materialName=NeoHookean "
      "\"ParameterSet=1862.0689655172414 18000\"\n"
      "region Liver sphere 0 0 0.04 0.025 54000\nset graphics@colorBy stress\nmouse " +
          std::to_string(static_cast<int>(organ.cx)) + " " + std::to_string(static_cast<int>(organ.cy)) +
          " 0.012\nwait 2\nscreenshot " + (dir / "stress.png").string() + "\nsave " + saved.string() + "\nquit\n");
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("Liver/FEM is now TetrahedronHyperelasticityFEMForceField"), std::string::npos)
      << run.output;
  EXPECT_GT(number_after(run.output, "max surface displacement"), 1.0) << run.output;

  // The stress view: no tissue colour left; the hot end of the map where it is pressed.
  auto stress = hof::render::read_png(dir / "stress.png");
  ASSERT_TRUE(stress);
  EXPECT_LT(tissue_coverage(*stress).share, 0.01);
  int hot = 0;
  for (int y = 0; y < stress->height; ++y) {
    for (int x = kPanelWidth; x < stress->width; ++x) {
      const std::uint8_t* p = &stress->rgb[3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(stress->width) +
                                                static_cast<std::size_t>(x))];
      if (p[0] > 170 && p[1] > 170 && p[2] < 110 && std::abs(x - organ.cx) < 150 && std::abs(y - organ.cy) < 150) ++hot;
    }
  }
  EXPECT_GT(hot, 30) << "no high stress drawn near the press";

  // The saved project holds the edited scene and the region, and builds that model.
  auto reloaded = hof::scene::read_project(saved);
  ASSERT_TRUE(reloaded) << reloaded.error().to_string();
  EXPECT_TRUE(reloaded->mechanics_scene.empty());
  EXPECT_NE(reloaded->mechanics_inline.find("TetrahedronHyperelasticityFEMForceField"), std::string::npos);
  // The youngModulus set on the replaced FEM went with it; the solver's, set in the same frame
  // as the switch (still queued then), is kept.
  ASSERT_EQ(reloaded->parameters.size(), 1u);
  EXPECT_EQ(reloaded->parameters[0].component, "solver");
  EXPECT_EQ(reloaded->parameters[0].parameter, "rayleighMass");
  EXPECT_EQ(reloaded->parameters[0].value, 0.3);
  ASSERT_EQ(reloaded->regions.size(), 1u);
  EXPECT_EQ(reloaded->regions[0].young_modulus_pa, 54000.0);
  EXPECT_EQ(reloaded->graphics.color_by, hof::scene::ColorBy::kStress);
  auto world = hof::scene::build_world(saved);
  ASSERT_TRUE(world) << world.error().to_string();
  const auto& config = *world->bodies[0].config;
  ASSERT_TRUE(config.force_fields[0].neo_hookean.has_value());
  EXPECT_EQ(config.ode.rayleigh_mass, 0.3);
  EXPECT_NEAR(config.force_fields[0].neo_hookean->young_modulus_pa, 5400.0, 1.0);
  EXPECT_TRUE(std::any_of(config.force_fields[0].neo_hookean->element_young_modulus_pa.begin(),
                          config.force_fields[0].neo_hookean->element_young_modulus_pa.end(),
                          [](double e) { return e == 54000.0; }));

  // An edit that names nothing stops the script with the names there are.
  const GuiRun refused = run_gui(dir, "remove mechanics/Liver/nothing\n");
  EXPECT_NE(refused.status, 0);
  EXPECT_NE(refused.output.find("no component 'nothing'"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("FEM"), std::string::npos) << refused.output;
}

TEST(GuiScript, ReadsTheToolTheTurnTheContactViewAndThePairSwitch) {
  auto ok = hof::app::parse_script(
      "tool capsule 0.08 0.006\ntool sphere 0.01\ntool mesh tool.stl\ntool mesh tool.stl 0.002\ntool point\n"
      "tool needle\nrotate 1 0 0 30\ncontacts on\npair Liver Stomach off\nshow contacts\nshow tool\n",
      "tool.txt");
  ASSERT_TRUE(ok) << ok.error().to_string();
  ASSERT_EQ(ok->size(), 11u);
  EXPECT_EQ((*ok)[0].kind, ScriptAction::Kind::kTool);
  EXPECT_EQ((*ok)[0].type, "capsule");
  EXPECT_EQ((*ok)[0].numbers, (std::vector<double>{0.08, 0.006}));  // shaft length, then radius
  EXPECT_EQ((*ok)[1].numbers, (std::vector<double>{0.01}));
  EXPECT_EQ((*ok)[2].file, "tool.stl");
  EXPECT_TRUE((*ok)[2].numbers.empty());
  EXPECT_EQ((*ok)[3].numbers, (std::vector<double>{0.002}));
  EXPECT_EQ((*ok)[4].type, "point");
  EXPECT_EQ((*ok)[5].type, "needle");
  EXPECT_EQ((*ok)[6].kind, ScriptAction::Kind::kRotate);
  EXPECT_EQ((*ok)[6].numbers, (std::vector<double>{1, 0, 0, 30}));
  EXPECT_EQ((*ok)[7].kind, ScriptAction::Kind::kContacts);
  EXPECT_TRUE((*ok)[7].on);
  EXPECT_EQ((*ok)[8].kind, ScriptAction::Kind::kPair);
  EXPECT_EQ((*ok)[8].element, "Liver");
  EXPECT_EQ((*ok)[8].attribute, "Stomach");
  EXPECT_FALSE((*ok)[8].on);
  EXPECT_EQ((*ok)[9].value, "contacts");
}

/// Pixels of the 3D view drawn in a contact point's colour (unlit: exact up to rounding).
std::size_t pixels_of(const hof::render::Image& image, int r, int g, int b) {
  std::size_t count = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = kPanelWidth; x < image.width; ++x) {
      const std::uint8_t* p = &image.rgb[3 * (static_cast<std::size_t>(y) * image.width + x)];
      if (std::abs(p[0] - r) <= 3 && std::abs(p[1] - g) <= 3 && std::abs(p[2] - b) <= 3) ++count;
    }
  }
  return count;
}

TEST(GuiWindow, TheToolMenuMountsACapsuleTheContactsAreDrawnAPairIsSwitchedOffAndTheToolSaved) {
  const fs::path dir = scratch("tool");
  const fs::path project = fs::path(HOF_SOURCE_DIR) / "examples/organs-in-contact.hof";
  const fs::path saved = dir / "with-tool.hof";
  const GuiRun run = run_gui(dir,
                             "wait 1.5\ncontacts on\nshow contacts\nscreenshot " + (dir / "contacts.png").string() +
                                 "\ntool capsule 0.08 0.006\nrotate 1 0 0 30\npair Liver Stomach off\nwait 1\n"
                                 "screenshot " +
                                 (dir / "tool.png").string() + "\nsave " + saved.string() + "\nquit\n",
                             project);
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find("the stylus carries a capsule"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("contact Stomach - Liver off"), std::string::npos) << run.output;
  // The liver rests on the stomach and the stomach on the support: their contact points are
  // drawn (orange on the first body of a contact, blue on the second).
  auto contacts = hof::render::read_png(dir / "contacts.png");
  ASSERT_TRUE(contacts) << contacts.error().to_string();
  EXPECT_GT(pixels_of(*contacts, 255, 153, 26) + pixels_of(*contacts, 77, 204, 255), 50u) << "no contact points drawn";
  // The saved project carries the capsule (length, then radius, as the script gave them).
  auto reloaded = hof::scene::read_project(saved);
  ASSERT_TRUE(reloaded) << reloaded.error().to_string();
  ASSERT_TRUE(reloaded->tool);
  EXPECT_EQ(reloaded->tool->shape, hof::procedures::ToolShape::kCapsule);
  EXPECT_DOUBLE_EQ(reloaded->tool->length_m, 0.08);
  EXPECT_DOUBLE_EQ(reloaded->tool->radius_m, 0.006);
  EXPECT_FALSE(reloaded->needle);
  // A tool whose mesh is not there is a clear error naming the file; the script stops.
  const GuiRun missing = run_gui(dir, "tool mesh /nonexistent/tool.stl\nquit\n", project);
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("/nonexistent/tool.stl"), std::string::npos) << missing.output;
}

TEST(GuiWindow, AScriptErrorNamesItsLineAndTheKnownNames) {
  const fs::path dir = scratch("errors");
  const GuiRun unknown_name = run_gui(dir, "wait 0\nset haptics/surface@stifness 0.4\nquit\n");
  EXPECT_NE(unknown_name.status, 0);
  EXPECT_NE(unknown_name.output.find("actions.txt:2"), std::string::npos) << unknown_name.output;
  EXPECT_NE(unknown_name.output.find("stiffness"), std::string::npos)
      << "the known attributes are listed: " << unknown_name.output;
  const GuiRun bad_value = run_gui(dir, "set haptics@renderer FastRenderer\n");
  EXPECT_NE(bad_value.status, 0);
  EXPECT_NE(bad_value.output.find("RuspiniRenderer"), std::string::npos) << bad_value.output;
  const GuiRun unknown_action = run_gui(dir, "wait 0\n\nfrobnicate\n");
  EXPECT_NE(unknown_action.status, 0);
  EXPECT_NE(unknown_action.output.find("actions.txt:3"), std::string::npos) << unknown_action.output;
}

TEST(GuiWindow, ARecordedDemonstrationReplaysHeadless) {
  const fs::path dir = scratch("record");
  const fs::path csv = dir / "demo.csv";
  // Find the organ, then press it for 1.5 s while recording; change a setting meanwhile.
  const GuiRun first = run_gui(dir, "wait 0.5\nscreenshot " + (dir / "view.png").string() + "\nquit\n");
  ASSERT_EQ(first.status, 0) << first.output;
  auto view = hof::render::read_png(dir / "view.png");
  ASSERT_TRUE(view);
  const Coverage organ = tissue_coverage(*view);
  const GuiRun demo =
      run_gui(dir, "wait 0.3\nrecord " + csv.string() + "\nmouse " + std::to_string(static_cast<int>(organ.cx)) + " " +
                       std::to_string(static_cast<int>(organ.cy)) +
                       " 0.012\nwait 1.5\nset haptics/surface@stiffness 0.3\nwait 0.3\nrecord off\nquit\n");
  ASSERT_EQ(demo.status, 0) << demo.output;
  const double touched_live = number_after(demo.output, "contact");
  ASSERT_GT(touched_live, 1.0) << demo.output;

  // The recording is a valid replay file at the haptic rate, with the event noted.
  auto samples = hof::haptics::load_replay(csv);
  ASSERT_TRUE(samples) << samples.error().to_string();
  EXPECT_GT(samples->size(), 1000u);
  EXPECT_GT(samples->back().t_s, 1.5);
  EXPECT_GT((samples->back().position_m - samples->front().position_m).norm(), 0.005) << "the stylus did not move";
  std::ifstream in(csv);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("# event "), std::string::npos);
  EXPECT_NE(text.find("haptics/surface@stiffness 0.3"), std::string::npos);

  // Its project replays it headless, deterministically: the liver is touched for about as long
  // (the stylus reaches it through the same path; the live run's simulation may lag a little).
  auto project = hof::scene::read_project(dir / "demo.hof");
  ASSERT_TRUE(project) << project.error().to_string();
  EXPECT_EQ(project->device, "replay:demo.csv");
  EXPECT_DOUBLE_EQ(project->surface.stiffness, 0.2) << "the project holds the settings the recording began with";
  for (const std::string& run : {"'" + (dir / "demo.hof").string() + "'",
                                 "'" + kLiverProject.string() + "' --device 'replay:" + csv.string() + "'"}) {
    const fs::path out = dir / "replay";
    fs::remove_all(out);
    const std::string command = "'" + std::string(HOF_BIN) + "' run " + run +
                                " --deterministic --seconds 2 --quiet --out '" + out.string() + "'";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream summary_file(out / "summary.json");
    const std::string summary((std::istreambuf_iterator<char>(summary_file)), std::istreambuf_iterator<char>());
    std::smatch m;
    ASSERT_TRUE(std::regex_search(summary, m, std::regex("\"contact_time_s\": ([0-9.e-]+)"))) << summary;
    EXPECT_NEAR(std::stod(m[1]), touched_live, 0.3) << command;
    EXPECT_NE(summary.find("\"fall_through_events\": 0"), std::string::npos) << summary;
  }
}

TEST(GuiWindow, StartsEmptyOpensAFileAndAFileThatDoesNotLoadLeavesTheWorldAsItWas) {
  const fs::path dir = scratch("open");
  const fs::path broken = dir / "broken.hof";
  std::ofstream(broken) << "<hof><mechanics scene='missing.scn'/></hof>\n";
  const GuiRun run =
      run_gui(dir,
              "wait 0.3\nscreenshot " + (dir / "empty.png").string() + "\nopen " + kLiverProject.string() +
                  "\nwait 0.5\nscreenshot " + (dir / "opened.png").string() + "\nopen " + broken.string() +
                  "\nopen /nonexistent/liver.hof\nwait 0.5\nscreenshot " + (dir / "after.png").string() + "\nquit\n",
              fs::path());
  ASSERT_EQ(run.status, 0) << run.output;
  auto empty = hof::render::read_png(dir / "empty.png");
  auto opened = hof::render::read_png(dir / "opened.png");
  auto after = hof::render::read_png(dir / "after.png");
  ASSERT_TRUE(empty && opened && after);
  EXPECT_LT(tissue_coverage(*empty).share, 0.001) << "an empty window draws no organ";
  const double share = tissue_coverage(*opened).share;
  EXPECT_GT(share, 0.04);
  EXPECT_NEAR(tissue_coverage(*after).share, share, 0.2 * share) << "a failed open changed the world";
  // Both failures are reported, naming the file.
  EXPECT_NE(run.output.find("broken.hof"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("missing.scn"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("/nonexistent/liver.hof"), std::string::npos) << run.output;
}

}  // namespace

// The window's typed graphics edit is checked as a project file's <graphics> is.
TEST(GuiTypedEdits, GraphicsAreCheckedAsTheProjectFileChecksThem) {
  hof::scene::GraphicsSetup g;
  EXPECT_TRUE(hof::scene::check_graphics(g));
  g.render_mode = hof::scene::RenderMode::kShadedWireframe;
  g.color_by = hof::scene::ColorBy::kStress;
  EXPECT_TRUE(hof::scene::check_graphics(g));
  hof::scene::GraphicsSetup bad = g;
  bad.transparency = 1.5;
  ASSERT_FALSE(hof::scene::check_graphics(bad));
  EXPECT_NE(hof::scene::check_graphics(bad).error().message.find("transparency must be in [0, 1]"), std::string::npos);
  bad = g;
  bad.light_direction = hof::Vec3::Zero();
  EXPECT_FALSE(hof::scene::check_graphics(bad));
  bad = g;
  bad.diffuse_color = hof::Vec3(0.2, 1.2, 0.0);
  EXPECT_FALSE(hof::scene::check_graphics(bad));
}
