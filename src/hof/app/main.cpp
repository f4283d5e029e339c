// The `hof` command: parses the command line (CLI11 lives in this file only, it is slow to
// compile) and hands over to the verbs in this folder.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

#include "hof/app/bench_command.h"
#include "hof/app/evaluation.h"
#include "hof/app/gui/gui_app.h"
#include "hof/app/mesh_commands.h"
#include "hof/app/run_command.h"
#include "hof/core/version.h"
#include "hof/haptics/device_backends/udp_auth.h"

namespace {

void add_mesh_commands(CLI::App& app, int& status) {
  CLI::App* mesh = app.add_subcommand("mesh", "Generate, inspect, convert and tetrahedralize meshes");
  mesh->require_subcommand(1);

  static hof::app::MeshInfoOptions info;
  CLI::App* info_cmd = mesh->add_subcommand(
      "info", "Print nodes, elements, surface, bounding box, volume, quality and problems of a mesh");
  info_cmd->add_option("file", info.file, "Mesh file (.msh, .obj, .stl, .off, .vtu)")->required();
  info_cmd->add_flag("--json", info.json, "Print the report as JSON");
  info_cmd->add_option("--unit", info.unit,
                       "Unit of the file's numbers (m, cm, mm): lengths are then reported in metres "
                       "(a mesh file does not state its unit)");
  info_cmd->add_flag("-q,--quiet", info.quiet, "No progress output");
  info_cmd->callback([&] { status = hof::app::run_mesh_info(info); });

  static hof::app::MeshGenerateOptions gen;
  CLI::App* gen_cmd =
      mesh->add_subcommand("generate", "Generate a standard organ model (writes OUT.msh and its surface as OUT.obj)");
  gen_cmd->add_option("shape", gen.shape, "Shape to generate")->check(CLI::IsMember({"liver"}))->required();
  gen_cmd
      ->add_option("-r,--resolution", gen.resolution,
                   "simple (~600 tets), coarse (~2,500), medium (~10,000) or fine (~40,000)")
      ->check(CLI::IsMember({"simple", "coarse", "medium", "fine"}))
      ->capture_default_str();
  gen_cmd->add_option("-o,--output", gen.output, "Output volume mesh (.msh, .vtu)")->required();
  gen_cmd->add_option("--msh-version", gen.msh_version, "Gmsh version to write: 2 or 4")
      ->check(CLI::IsMember({2, 4}))
      ->capture_default_str();
  gen_cmd->add_flag("-q,--quiet", gen.quiet, "No progress output");
  gen_cmd->callback([&] { status = hof::app::run_mesh_generate(gen); });

  static hof::app::MeshTetrahedralizeOptions tet;
  CLI::App* tet_cmd =
      mesh->add_subcommand("tetrahedralize", "Fill a closed triangle surface with quality tetrahedra (TetGen)");
  tet_cmd->add_option("surface", tet.surface, "Closed surface (.obj, .stl, .off, .msh)")->required();
  tet_cmd->add_option("-o,--output", tet.output, "Output volume mesh (.msh, .vtu)")->required();
  tet_cmd->add_option("--max-volume", tet.max_volume_m3, "Largest tetrahedron volume in m^3 (0 = no bound)")
      ->capture_default_str();
  tet_cmd
      ->add_option("--quality", tet.quality,
                   "Radius-edge ratio bound (>= 1; smaller is better shaped; 0 = no refinement)")
      ->capture_default_str();
  tet_cmd->add_option("--min-dihedral", tet.min_dihedral_deg, "Dihedral angle to aim for, degrees")
      ->capture_default_str();
  tet_cmd->add_flag("--preserve-surface", tet.preserve_surface, "Do not split surface triangles");
  tet_cmd->add_option("--msh-version", tet.msh_version, "Gmsh version to write: 2 or 4")
      ->check(CLI::IsMember({2, 4}))
      ->capture_default_str();
  tet_cmd->add_flag("-q,--quiet", tet.quiet, "No progress output");
  tet_cmd->callback([&] { status = hof::app::run_mesh_tetrahedralize(tet); });

  static hof::app::MeshConvertOptions conv;
  CLI::App* conv_cmd = mesh->add_subcommand("convert", "Convert between mesh formats (chosen from the extensions)");
  conv_cmd->add_option("input", conv.input, "Input mesh")->required();
  conv_cmd->add_option("output", conv.output, "Output mesh (.msh, .vtu, .obj, .off)")->required();
  conv_cmd->add_option("--msh-version", conv.msh_version, "Gmsh version to write: 2 or 4")
      ->check(CLI::IsMember({2, 4}))
      ->capture_default_str();
  conv_cmd->add_flag("-q,--quiet", conv.quiet, "No progress output");
  conv_cmd->callback([&] { status = hof::app::run_mesh_convert(conv); });
}

// The choices of --keep-cpus-awake and of --pin-threads (`hof run` and `hof gui`).
const std::map<std::string, hof::haptics::KeepAwake> kKeepAwakeModes{{"auto", hof::haptics::KeepAwake::automatic},
                                                                     {"on", hof::haptics::KeepAwake::on},
                                                                     {"off", hof::haptics::KeepAwake::off}};
const std::map<std::string, bool> kOnOff{{"on", true}, {"off", false}};

// `hof run`: a session without a window.
void add_run_command(CLI::App& app, int& status) {
  static hof::app::RunOptions run;
  static double seconds = 0.0;
  static long steps = 0;
  static std::vector<std::string> run_devices;  // hof run: --device, once per hand
  static std::string tool;
  static std::string out;
  CLI::App* run_cmd =
      app.add_subcommand("run", "Run a haptic session on a project (.hof), SOFA scene (.scn) or X3D scene (.x3d)");
  run_cmd->add_option("file", run.file, "Project (.hof), SOFA scene (.scn) or X3D scene (.x3d)")->required();
  run_cmd->add_flag("--headless", run.headless, "No window (the default; `hof gui` is the window)");
  run_cmd->add_flag("--deterministic", run.deterministic,
                    "Virtual time: loops in lock-step, identical output every run");
  auto* seconds_opt =
      run_cmd->add_option("--seconds", seconds,
                          "Length of the run in seconds (default 5, or a scripted motion's whole length when longer)");
  auto* steps_opt = run_cmd->add_option("--steps", steps, "Length of the run in simulation steps");
  seconds_opt->excludes(steps_opt);
  run_cmd->add_option("--device", run_devices,
                      "Device spec, e.g. scripted:poke, replay:FILE.csv, udp:5005, virtual-hand:poke; given again: "
                      "the next hand's (a project with <tool device=...>)");
  run_cmd->add_option("--tool", tool,
                      "A tool with a shape on the stylus, as the project's <tool>: sphere,radius=0.005 | "
                      "capsule,radius=0.004,length=0.05[,orientation=0 1 0 1.57] | mesh,mesh=FILE.stl");
  run_cmd->add_option("--out", out, "Folder for telemetry.csv, summary.json, the final state (.vtu) and plots");
  run_cmd->add_option("--telemetry-rate", run.telemetry_rate_hz,
                      "Rows per second in telemetry.csv (0 = every haptic tick)");
  run_cmd->add_flag("-q,--quiet", run.quiet, "No progress output");
  run_cmd
      ->add_option("--keep-cpus-awake", run.keep_awake,
                   "auto|on|off: real time, keep the CPUs from halting so the haptic thread wakes on time (auto: on a "
                   "virtual machine; docs/reliability.md)")
      ->transform(CLI::CheckedTransformer(kKeepAwakeModes, CLI::ignore_case))
      ->default_str("auto");
  run_cmd
      ->add_option(
          "--pin-threads", run.pin_threads,
          "on|off: real time, the haptic loop on the last CPU, the simulation on the others (docs/performance.md)")
      ->transform(CLI::CheckedTransformer(kOnOff, CLI::ignore_case))
      ->default_str("on");
  run_cmd
      ->add_option("--sim-threads", run.simulation_threads,
                   "Real time: the simulation's threads (0 = automatic: every core but one, left to the haptic loop)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  run_cmd->callback([&, seconds_opt, steps_opt] {
    if (seconds_opt->count()) run.seconds = seconds;
    if (steps_opt->count()) run.steps = steps;
    if (!run_devices.empty() && !run_devices.front().empty()) run.device = run_devices.front();
    if (run_devices.size() > 1) run.more_devices.assign(run_devices.begin() + 1, run_devices.end());
    if (!tool.empty()) run.tool = tool;
    if (!out.empty()) run.out = out;
    status = hof::app::run_session(run);
  });
}

// `hof bench`: the evaluation, or one scene timed with --scene.
void add_bench_command(CLI::App& app, int& status) {
  static hof::app::BenchOptions bench;
  static hof::app::EvaluationOptions evaluation;
  CLI::App* bench_cmd =
      app.add_subcommand("bench",
                         "Re-run the thesis' evaluation on this machine (tables, results.json/.csv, plots, report.md), "
                         "or with --scene time "
                         "one scene's mechanics as fast as it goes (compare with runSofa -g batch -n N)");
  CLI::Option* scene_opt = bench_cmd->add_option(
      "--scene", bench.scene, "Time this project (.hof), SOFA scene (.scn) or X3D scene (.x3d) alone");
  bench_cmd->add_option("--steps", bench.steps, "With --scene: simulation steps to time")->capture_default_str();
  bench_cmd->add_option("--threads", bench.threads, "With --scene: threads (0 = all cores)")->capture_default_str();
  bench_cmd->add_flag("--json", bench.json, "With --scene: print the figures as JSON");
  CLI::Option* quick_opt =
      bench_cmd->add_flag("--quick", evaluation.quick, "The evaluation in seconds: the smallest liver, short batches");
  CLI::Option* only_opt =
      bench_cmd->add_option("--only", evaluation.only, "Only the cells whose name matches this regular expression");
  CLI::Option* out_opt = bench_cmd->add_option("--out", evaluation.out, "Folder for the report")->capture_default_str();
  for (CLI::Option* o : {quick_opt, only_opt, out_opt}) o->excludes(scene_opt);
  bench_cmd->callback([&status, scene_opt, out_opt] {
    if (scene_opt->count()) {
      status = hof::app::run_bench(bench);
      return;
    }
    evaluation.command_line = "hof bench";
    if (evaluation.quick) evaluation.command_line += " --quick";
    if (!evaluation.only.empty()) evaluation.command_line += " --only '" + evaluation.only + "'";
    if (out_opt->count()) evaluation.command_line += " --out " + evaluation.out.string();
    status = hof::app::run_evaluation(evaluation);
  });
}

// `hof gui`: the window.
void add_gui_command(CLI::App& app, int& status) {
  static hof::app::GuiOptions gui;
  static std::string gui_file, gui_script, gui_size;
  CLI::App* gui_cmd = app.add_subcommand(
      "gui", "The window: see, touch (the mouse is the stylus when no device is connected), tune, save");
  gui_cmd->add_option("file", gui_file, "Project (.hof), SOFA scene (.scn) or X3D scene (.x3d)");
  gui_cmd->add_option("--device", gui.device, "Device spec (default: the project's; the mouse when it has none)");
  gui_cmd->add_option("--script", gui_script, "Run the actions of this file (one per line), then exit");
  gui_cmd->add_option("--size", gui_size, "Window size WIDTHxHEIGHT (default 1280x720)");
  gui_cmd->add_flag("-q,--quiet", gui.quiet, "No messages on the terminal");
  gui_cmd
      ->add_option(
          "--keep-cpus-awake", gui.keep_awake,
          "auto|on|off: keep the CPUs from halting so the haptic thread wakes on time (auto: on a virtual machine)")
      ->transform(CLI::CheckedTransformer(kKeepAwakeModes, CLI::ignore_case))
      ->default_str("auto");
  gui_cmd
      ->add_option("--pin-threads", gui.pin_threads,
                   "on|off: the haptic loop on the last CPU, the simulation on the others")
      ->transform(CLI::CheckedTransformer(kOnOff, CLI::ignore_case))
      ->default_str("on");
  gui_cmd
      ->add_option(
          "--sim-threads", gui.simulation_threads,
          "The simulation's threads (0 = automatic: every core but one, left to the haptic loop and the window)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  gui_cmd->callback([&] {
    if (!gui_file.empty()) gui.file = gui_file;
    if (!gui_script.empty()) gui.script = gui_script;
    if (!gui_size.empty()) {
      int w = 0, h = 0;
      if (std::sscanf(gui_size.c_str(), "%dx%d", &w, &h) != 2 || w < 320 || h < 240 || w > 8192 || h > 8192) {
        std::fprintf(stderr, "hof: --size must be WIDTHxHEIGHT within 320x240 and 8192x8192, got '%s'\n",
                     gui_size.c_str());
        status = 2;
        return;
      }
      gui.width = w;
      gui.height = h;
    }
    status = hof::app::run_gui(gui);
  });
}

// `hof check`: a project, scene or mesh validated.
void add_check_command(CLI::App& app, int& status) {
  static hof::app::CheckOptions check;
  CLI::App* check_cmd = app.add_subcommand("check", "Validate a project, scene or mesh and print every problem");
  check_cmd->add_option("file", check.file, "File to check")->required();
  check_cmd->callback([&] { status = hof::app::run_check(check); });
}

// `hof device`: the device tools.
void add_device_commands(CLI::App& app, int& status) {
  CLI::App* device_cmd = app.add_subcommand("device", "Haptic device tools");
  device_cmd->require_subcommand(1);
  static std::string key_file;
  CLI::App* keygen = device_cmd->add_subcommand(
      "keygen", "Write a new shared key for a UDP bridge on another machine (udp:HOST:PORT,key=FILE)");
  keygen->add_option("file", key_file, "Key file to create (mode 0600; never overwritten)")->required();
  keygen->callback([&] {
    if (auto written = hof::haptics::udp::write_new_key_file(key_file); !written) {
      std::fprintf(stderr, "hof: %s\n", written.error().to_string().c_str());
      status = 1;
      return;
    }
    std::printf("wrote a new key to %s: copy it to the bridge's machine over a secure channel (scp)\n",
                key_file.c_str());
  });
}

// The commands past `hof mesh`: run, bench, gui, check and device.
void add_run_commands(CLI::App& app, int& status) {
  add_run_command(app, status);
  add_bench_command(app, status);
  add_gui_command(app, status);
  add_check_command(app, status);
  add_device_commands(app, status);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"HoF - Haptics Open Framework: touch deformable soft-tissue models"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("hof ") + HOF_VERSION_STRING);
  int status = 0;
  add_mesh_commands(app, status);
  add_run_commands(app, status);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    // Every error of the command starts with "hof:", as the verbs' own do.
    std::fprintf(stderr, "hof: %s (see hof --help)\n", e.what());
    return e.get_exit_code();
  }
  return status;
}
