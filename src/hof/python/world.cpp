// hof.World: a world loaded by the one builder, stepped and run in virtual or real time through
// the same Session and the same run recording as `hof run`, its state as numpy arrays, its
// settings through the command seam.

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hof/app/session_recording.h"
#include "hof/coupling/session.h"
#include "hof/python/bindings.h"
#include "hof/python/common.h"
#include "hof/python/function_device.h"
#include "hof/python/run_report.h"
#include "hof/scene/device_config.h"
#include "hof/scene/model_parameters.h"
#include "hof/scene/project.h"
#include "hof/scene/project_edit.h"
#include "hof/scene/world.h"

namespace hof::python {
namespace {

class PyWorld {
 public:
  PyWorld(scene::World world, std::unique_ptr<coupling::Session> session)
      : world_(std::make_unique<scene::World>(std::move(world))), session_(std::move(session)) {}
  ~PyWorld() {
    // The session (and its device, which may hold a Python function) goes first, without
    // the GIL: its threads end.
    py::gil_scoped_release release;
    session_.reset();
  }

  static std::unique_ptr<PyWorld> load(const std::filesystem::path& path, const std::string& device,
                                       const std::string& tool) {
    Expected<scene::World> world = [&] {
      py::gil_scoped_release release;
      return scene::build_world(path, device);
    }();
    if (!world) raise(world.error());
    if (!tool.empty()) {
      auto config = scene::parse_tool_spec(tool);
      if (!config) raise(config.error());
      if (auto mounted = scene::mount_tool(*world, *config); !mounted) raise(mounted.error());
    }
    return make(std::move(*world));
  }

  static std::unique_ptr<PyWorld> make(scene::World world) {
    auto device = scene::open_device(world.device);
    if (!device) {
      Error e = device.error();
      e.message = fmt::format("{} (device of {})", e.message, world.file.string());
      raise(e);
    }
    coupling::SessionConfig config = world.config;
    // Only a real-time run has a haptic thread to raise; virtual time ignores it.
    config.haptics.realtime_priority = true;
    // The project's other hands (<tool device=…>), each on its own device.
    std::vector<std::unique_ptr<haptics::Device>> more_devices;
    for (coupling::HandConfig& hand : config.more_hands) {
      hand.haptics.realtime_priority = true;
      auto opened = scene::open_device(hand.device);
      if (!opened) {
        Error e = opened.error();
        e.message = fmt::format("{} (a <tool>'s device in {})", e.message, world.file.string());
        raise(e);
      }
      more_devices.push_back(std::move(*opened));
    }
    auto session =
        coupling::Session::make(std::move(world.bodies), std::move(*device), std::move(more_devices), config);
    if (!session) raise(session.error());
    return std::make_unique<PyWorld>(std::move(world), std::move(*session));
  }

  [[nodiscard]] std::string name() const { return world_->name; }
  [[nodiscard]] std::filesystem::path file() const { return world_->file; }
  [[nodiscard]] std::string device() const { return device_spec_.empty() ? world_->device : device_spec_; }
  [[nodiscard]] double dt() const { return session_->dt(); }
  [[nodiscard]] double time() const { return session_->simulated_time(); }
  [[nodiscard]] std::string length_unit() const { return world_->length_unit; }
  [[nodiscard]] std::vector<std::string> body_names() const {
    std::vector<std::string> names;
    for (std::size_t i = 0; i < session_->body_count(); ++i) names.push_back(session_->body(i).name);
    return names;
  }
  [[nodiscard]] std::vector<std::string> defaults() const { return world_->defaults; }
  [[nodiscard]] std::vector<std::string> warnings() const { return world_->warnings; }

  // A body by index (negative from the end) or name.
  std::size_t body_index(const py::object& body) const {
    const std::size_t n = session_->body_count();
    if (py::isinstance<py::str>(body)) {
      const std::string name = body.cast<std::string>();
      for (std::size_t i = 0; i < n; ++i) {
        if (session_->body(i).name == name) return i;
      }
      std::string names;
      for (std::size_t i = 0; i < n; ++i) names += (names.empty() ? "'" : ", '") + session_->body(i).name + "'";
      throw py::key_error(fmt::format("no body '{}' in this world (its bodies: {})", name, names));
    }
    if (!py::isinstance<py::int_>(body)) throw py::type_error("a body is named by its index (int) or its name (str)");
    const auto i = body.cast<std::int64_t>();
    const std::int64_t at = i < 0 ? i + static_cast<std::int64_t>(n) : i;
    if (at < 0 || at >= static_cast<std::int64_t>(n)) {
      throw py::index_error(
          fmt::format("body index {} is out of range: this world has {} bod{}", i, n, n == 1 ? "y" : "ies"));
    }
    return static_cast<std::size_t>(at);
  }
  const coupling::SessionBody& deformable(const py::object& body, std::size_t* index = nullptr) const {
    const std::size_t i = body_index(body);
    if (index) *index = i;
    const coupling::SessionBody& b = session_->body(i);
    if (!b.deformable())
      throw py::value_error(fmt::format("body '{}' is a rigid shape: it has no nodes (use surface())", b.name));
    return b;
  }

  py::array_t<double> positions(const py::object& body) const {
    std::size_t i = 0;
    deformable(body, &i);
    return flat_points_array(session_->state(i).x);
  }
  py::array_t<double> velocities(const py::object& body) const {
    std::size_t i = 0;
    deformable(body, &i);
    return flat_points_array(session_->state(i).v);
  }
  py::array_t<double> forces(const py::object& body) const {
    std::size_t i = 0;
    deformable(body, &i);
    return flat_points_array(session_->state(i).f);
  }
  py::array_t<double> rest_positions(const py::object& body) const {
    return points_array(deformable(body).model->rest_positions);
  }
  py::array_t<std::int32_t> tets(const py::object& body) const { return index_array(deformable(body).model->tets); }
  py::array_t<double> masses(const py::object& body) const {
    const auto& m = deformable(body).model->node_mass_kg;
    py::array_t<double> out(static_cast<py::ssize_t>(m.size()));
    std::copy(m.begin(), m.end(), out.mutable_data());
    return out;
  }
  std::vector<std::int32_t> fixed_nodes(const py::object& body) const {
    const auto& dofs = deformable(body).model->fixed_dofs;
    std::vector<std::int32_t> nodes;
    for (const std::int32_t d : dofs) {
      if (nodes.empty() || nodes.back() != d / 3) nodes.push_back(d / 3);
    }
    return nodes;
  }

  // The touchable surface as it is now (a rigid shape's never moves).
  std::vector<Vec3> current_surface(std::size_t i) const {
    const coupling::SessionBody& b = session_->body(i);
    std::vector<Vec3> vertices = b.surface.vertices;
    if (b.deformable()) {
      const Eigen::VectorXd& x = session_->state(i).x;
      b.mapping.apply(std::span<const double>(x.data(), static_cast<std::size_t>(x.size())), vertices);
    }
    return vertices;
  }
  py::tuple surface(const py::object& body) const {
    const std::size_t i = body_index(body);
    return py::make_tuple(points_array(current_surface(i)), index_array(session_->body(i).surface.triangles));
  }
  // Unit vertex normals of the surface as it is now: the area-weighted mean of the normals of
  // the triangles around each vertex (as the haptic snapshot's).
  py::array_t<double> normals(const py::object& body) const {
    const std::size_t i = body_index(body);
    const std::vector<Vec3> v = current_surface(i);
    std::vector<Vec3> n(v.size(), Vec3::Zero());
    for (const mesh::Tri& t : session_->body(i).surface.triangles) {
      const Vec3 area_normal = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);  // twice the area, along the normal
      for (int k = 0; k < 3; ++k) n[t[k]] += area_normal;
    }
    for (Vec3& x : n) {
      const double length = x.norm();
      x = length > 0.0 ? Vec3(x / length) : Vec3::Zero();
    }
    return points_array(n);
  }

  py::object contact() const {
    if (!last_sample_ || !last_sample_->valid) return py::none();
    const haptics::HapticSample& s = *last_sample_;
    py::dict d;
    d["time"] = s.time_s;
    d["in_contact"] = s.contact;
    std::int32_t b = s.contact && s.triangle >= 0 ? session_->body_of_triangle(s.triangle, s.layer) : -1;
    if (s.tool.active && s.tool.body >= 0) b = s.tool.body;
    d["body"] = b >= 0 ? py::object(py::str(session_->body(static_cast<std::size_t>(b)).name)) : py::none();
    d["triangle"] = s.contact ? s.triangle : -1;
    d["barycentric"] = vec3_array(s.barycentric);
    d["point"] = vec3_array(s.contact_point);
    d["normal"] = vec3_array(s.contact_normal);
    d["force"] = vec3_array(s.force);
    d["device"] = vec3_array(s.device);
    d["proxy"] = vec3_array(s.proxy);
    d["penetration"] = s.penetration_m;
    return d;
  }

  // ---- settings through the command seam

  static std::pair<std::string, std::string> split_target(const std::string& target) {
    const std::size_t slash = target.find('/');
    if (slash == std::string::npos) return {target, ""};
    return {target.substr(0, slash), target.substr(slash + 1)};
  }
  static bool project_setting(const std::string& target) {
    return target == "haptics" || target.starts_with("haptics/") || target == "graphics" ||
           target.starts_with("graphics/");
  }
  void set(const std::string& target, const std::string& parameter, const py::object& value) {
    if (project_setting(target)) return set_project(target, parameter, value);
    if (!py::isinstance<py::float_>(value) && !py::isinstance<py::int_>(value)) {
      throw py::type_error(fmt::format("{} {}: a mechanics parameter is a number, got {}", target, parameter,
                                       py::repr(value).cast<std::string>()));
    }
    const auto [body, component] = split_target(target);
    const auto command = scene::parameter_command(*session_, body, component, parameter, value.cast<double>());
    ok_or_raise(command ? session_->submit(*command) : Expected<void>(std::unexpected(command.error())));
  }
  // A setting of the project file (the window's panels): checked as when the file is read,
  // carried to the session by the commands the window sends, kept for save().
  void set_project(const std::string& element, const std::string& attribute, const py::object& value) {
    std::string text;
    if (py::isinstance<py::bool_>(value))
      text = value.cast<bool>() ? "true" : "false";
    else if (py::isinstance<py::str>(value))
      text = value.cast<std::string>();
    else if (py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value))
      text = py::repr(value).cast<std::string>();
    else
      throw py::type_error(fmt::format("{}@{}: a setting is a number, a bool or a string", element, attribute));
    if (element == "haptics" && attribute == "device") {
      switch_device(py::str(text), true);
      world_->project.device = text;
      return;
    }
    auto edit = scene::parse_project_edit(world_->project, world_->file, element, attribute, text);
    if (!edit) {
      Error e = edit.error();
      e.code = ErrorCode::kInvalidArgument;  // a value the caller gave, not a file that does not parse
      raise(e);
    }
    scene::HofProject next = world_->project;
    scene::apply_edit(next, *edit);
    const auto commands = scene::live_commands(next, *edit, body_names());
    for (const coupling::Command& c : commands.value_or(std::vector<coupling::Command>{}))
      ok_or_raise(session_->submit(c));
    world_->project = std::move(next);
    if (!commands) {
      PyErr_WarnEx(PyExc_UserWarning,
                   fmt::format("{}@{} is saved with the project; it takes effect when the project is loaded again",
                               element, attribute)
                       .c_str(),
                   1);
    }
  }
  double get(const std::string& target, const std::string& parameter) const {
    const auto [body, component] = split_target(target);
    return value_or_raise(scene::session_parameter(*session_, body, component, parameter));
  }
  std::vector<std::string> parameters(const py::object& body) const {
    const coupling::SessionBody& b = deformable(body);
    std::vector<std::string> names;
    if (b.config) {
      for (const std::string& n : scene::parameter_names(*b.config)) names.push_back(b.name + "/" + n);
    }
    return names;
  }
  void set_force_limit(double newtons) { ok_or_raise(session_->submit(coupling::command::SetForceLimit{newtons})); }

  void save(const std::filesystem::path& path) {
    if (world_->file.extension() == ".x3d") {
      raise(Error{ErrorCode::kUnsupported,
                  "an X3D scene cannot be saved as a project yet (the project format holds SOFA scenes)", path.string(),
                  0, -1});
    }
    scene::HofProject out = scene::moved_project(world_->project, world_->file, path);
    if (world_->default_probe) out.device = "auto";  // the probe is fitted again when it is read
    scene::record_changes(out, *session_);
    // And those accepted but not applied yet (no step since they were set).
    scene::record_parameters(out, scene::parameter_changes(*session_, /*with_queued=*/true));
    ok_or_raise(scene::write_project(out, path));
  }

  // ---- running

  void step(long steps) {
    if (steps < 0) throw py::value_error(fmt::format("steps must be >= 0, got {}", steps));
    if (steps == 0) return;
    run_session(static_cast<double>(steps) * session_->dt(), true, nullptr);
  }

  py::tuple run(std::optional<double> seconds, const py::object& device, bool deterministic, double telemetry_rate,
                const std::optional<std::filesystem::path>& out, bool quiet) {
    if (seconds && !(*seconds > 0.0 && *seconds <= 86400.0)) {
      throw py::value_error(fmt::format("seconds must be in (0, 86400], got {}", *seconds));
    }
    if (!(telemetry_rate >= 0.0 && telemetry_rate <= 100000.0)) {
      throw py::value_error(
          fmt::format("telemetry_rate must be in [0, 100000] rows/s (0 = every tick), got {}", telemetry_rate));
    }
    if (!device.is_none()) switch_device(device, deterministic);
    const double length = seconds.value_or(app::default_run_seconds(*session_));
    app::RunRecording recording(*session_, *world_, telemetry_rate);
    Telemetry telemetry;
    const coupling::SessionReport report = run_session(length, deterministic, [&](const haptics::HapticSample& s) {
      if (const app::TelemetryRow* row = recording.add(s)) telemetry.rows.push_back(*row);
    });
    app::RunConditions conditions;
    conditions.deterministic = deterministic;
    conditions.keep_awake = deterministic ? "off (virtual time)" : "off (Python)";
    const std::string summary = recording.summary_json(report, conditions);
    if (out) write_report(*out, recording, report, summary, telemetry, quiet);
    py::object json = py::module_::import("json");
    return py::make_tuple(json.attr("loads")(summary), columns(recording, telemetry, *session_));
  }

 private:
  void switch_device(const py::object& device, bool deterministic) {
    coupling::command::SetDevice command;
    if (py::isinstance<py::str>(device)) {
      command.label = device.cast<std::string>();
      device_spec_ = command.label;
      // Parsed and opened here, so that an error names the spec (scene/ is where strings end).
      auto config = scene::parse_device_spec(command.label);
      if (!config) ok_or_raise(std::unexpected(config.error()));
      auto opened = scene::open_device(command.label);
      if (!opened) ok_or_raise(std::unexpected(opened.error()));
      command.config = std::move(*config);
      command.opened = std::shared_ptr<haptics::Device>(std::move(*opened));
    } else if (PyCallable_Check(device.ptr())) {
      if (!deterministic) {
        throw py::value_error(
            "a Python function as the device runs in virtual time only (deterministic=True): in real time it "
            "would hold the haptic thread to the interpreter");
      }
      command.label = "python-function";
      command.opened = std::make_shared<FunctionDevice>(device.cast<py::function>(), device_error_, running_);
      device_spec_ = "a Python function (world frame)";
      // Its positions are in the world frame.
      ok_or_raise(session_->submit(command));
      ok_or_raise(session_->submit(coupling::command::SetCalibration{haptics::Calibration{}}));
      return;
    } else {
      throw py::type_error("device must be a spec string (e.g. 'scripted:poke') or a function t -> (x, y, z)");
    }
    ok_or_raise(session_->submit(command));
  }

  coupling::SessionReport run_session(double seconds, bool deterministic,
                                      const std::function<void(const haptics::HapticSample&)>& on_sample) {
    PendingPythonError interrupt;
    running_ = session_.get();
    // Every few steps: a pending signal (Ctrl-C) stops the run after the current step.
    const ProgressSink progress = [&](std::string_view, double) {
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) {
        interrupt.fetch();
        session_->request_stop();
      }
    };
    std::optional<haptics::HapticSample> last;
    const auto record = [&](const haptics::HapticSample& s) {
      last = s;
      if (on_sample) on_sample(s);
    };
    coupling::SessionReport report;
    {
      py::gil_scoped_release release;
      report = deterministic ? session_->run_virtual(seconds, record, progress)
                             : session_->run_realtime(seconds, record, progress);
    }
    running_ = nullptr;
    if (last) last_sample_ = last;
    if (device_error_.set()) device_error_.raise();
    if (interrupt.set()) interrupt.raise();
    if (report.diverged) {
      PyErr_SetString(hof_error_type, fmt::format("the simulation diverged: {}", report.divergence).c_str());
      throw py::error_already_set();
    }
    return report;
  }

  std::unique_ptr<scene::World> world_;  // its bodies are the session's
  std::unique_ptr<coupling::Session> session_;
  coupling::Session* running_{nullptr};  // the session while a run is going (a device may stop it)
  PendingPythonError device_error_;
  std::string device_spec_;
  std::optional<haptics::HapticSample> last_sample_;
};

}  // namespace

void bind_world(py::module_& module) {
  py::class_<PyWorld>(module, "World", "A world of bodies and its haptic session (hof.load() makes one).")
      .def_static("load", &PyWorld::load, py::arg("path"), py::arg("device") = "", py::arg("tool") = "",
                  "Builds the world of a .hof project, SOFA .scn or X3D scene (the builder `hof run` uses). `device` "
                  "replaces the file's device (a spec string, as --device); `tool` mounts a tool with a shape on "
                  "the stylus (a spec string, as --tool: 'capsule,radius=0.004,length=0.05').")
      .def_property_readonly("name", &PyWorld::name)
      .def_property_readonly("file", &PyWorld::file)
      .def_property_readonly("device", &PyWorld::device, "The device spec in use.")
      .def_property_readonly("dt", &PyWorld::dt, "The simulation step, s.")
      .def_property_readonly("time", &PyWorld::time, "Simulated time so far, s.")
      .def_property_readonly("length_unit", &PyWorld::length_unit)
      .def_property_readonly("bodies", &PyWorld::body_names, "The bodies' names, in order.")
      .def_property_readonly("defaults", &PyWorld::defaults, "Every default the builder used: 'what = value (why)'.")
      .def_property_readonly("warnings", &PyWorld::warnings)
      .def("step", &PyWorld::step, py::arg("steps") = 1,
           "Advances the world `steps` simulation steps in virtual time (the device plays meanwhile).")
      .def(
          "run", &PyWorld::run, py::arg("seconds") = py::none(), py::arg("device") = py::none(),
          py::arg("deterministic") = true, py::arg("telemetry_rate") = 0.0, py::arg("out") = py::none(),
          py::arg("quiet") = true,
          "Runs a haptic session (as `hof run`); returns (report, telemetry): summary.json as a dict and the telemetry "
          "columns as numpy arrays.")
      .def("positions", &PyWorld::positions, py::arg("body") = 0, "(n, 3) node positions, m (a copy).")
      .def("velocities", &PyWorld::velocities, py::arg("body") = 0, "(n, 3) node velocities, m/s (a copy).")
      .def("forces", &PyWorld::forces, py::arg("body") = 0,
           "(n, 3) total force on each node at the last step, N (a copy).")
      .def("rest_positions", &PyWorld::rest_positions, py::arg("body") = 0, "(n, 3) rest positions, m (a copy).")
      .def("tets", &PyWorld::tets, py::arg("body") = 0, "(m, 4) int32 tetrahedra (a copy).")
      .def("masses", &PyWorld::masses, py::arg("body") = 0, "(n,) lumped node masses, kg (a copy).")
      .def("fixed_nodes", &PyWorld::fixed_nodes, py::arg("body") = 0, "Nodes held on at least one axis.")
      .def("surface", &PyWorld::surface, py::arg("body") = 0,
           "(vertices (v, 3) m, triangles (f, 3) int32): the touchable surface as it is now (copies).")
      .def("normals", &PyWorld::normals, py::arg("body") = 0, "(v, 3) unit vertex normals of the surface as it is now.")
      .def("contact", &PyWorld::contact, "The last haptic tick's contact as a dict (None before any run).")
      .def(
          "set", &PyWorld::set, py::arg("target"), py::arg("parameter"), py::arg("value"),
          "Sets a parameter through the command seam, e.g. set('Liver/FEM', 'youngModulus', 8000), or a setting of the "
          "project by the file's names, e.g. set('haptics/surface', 'stiffness', 0.4), set('haptics', 'renderer', "
          "'GodObjectRenderer'); applied before the next step. Checked now: a bad value raises ValueError with the "
          "command line's message.")
      .def("get", &PyWorld::get, py::arg("target"), py::arg("parameter"),
           "A parameter's value as the accepted commands leave it.")
      .def("parameters", &PyWorld::parameters, py::arg("body") = 0,
           "Every 'Body/component/parameter' set() takes for a body.")
      .def("set_force_limit", &PyWorld::set_force_limit, py::arg("newtons"),
           "A force limit below the device's (0: the device's).")
      .def("save", &PyWorld::save, py::arg("path"),
           "Writes the world as a .hof project, with the parameters changed so far.");
}

}  // namespace hof::python
