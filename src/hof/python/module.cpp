// The `hof` Python module (pybind11): worlds loaded by the one builder, stepped and run in
// virtual or real time through the same Session and the same run recording as `hof run`,
// their state as numpy arrays, their settings through the command seam, and the mesh tools.
// docs/python.md is the user's guide; the package's Python part is hof/__init__.py.
//
// Threads: the GIL is released while C++ works (a step, a run, meshing). A run calls back
// into Python only with the GIL taken again: a function device (virtual time only, on the
// caller's thread) and every few steps a look for a pending signal, so that Ctrl-C stops a
// run after its current step and raises KeyboardInterrupt with the world intact.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "hof/app/session_recording.h"
#include "hof/core/file_write.h"
#include "hof/coupling/session.h"
#include "hof/haptics/device.h"
#include "hof/mechanics/model_parameters.h"
#include "hof/mesh/liver_generator.h"
#include "hof/mesh/mesh_io.h"
#include "hof/mesh/mesh_report.h"
#include "hof/mesh/tetrahedralize.h"
#include "hof/procedures/needle.h"
#include "hof/scene/device_config.h"
#include "hof/scene/project.h"
#include "hof/scene/world.h"

namespace py = pybind11;

namespace hof::python {
namespace {

// ---- errors -------------------------------------------------------------------------------

PyObject* hof_error_type = nullptr;  // hof.Error (a RuntimeError), set at import

// An Error as a Python exception with the message the command line prints: a missing file is
// FileNotFoundError, another I/O failure OSError, a value out of range ValueError, the rest
// hof.Error.
[[noreturn]] void raise(const Error& e) {
  const std::string text = e.to_string();
  if (e.code == ErrorCode::kIo) {
    const bool missing = e.message.find("no such file") != std::string::npos || e.message.find("not found") != std::string::npos;
    PyErr_SetString(missing ? PyExc_FileNotFoundError : PyExc_OSError, text.c_str());
  } else if (e.code == ErrorCode::kInvalidArgument) {
    PyErr_SetString(PyExc_ValueError, text.c_str());
  } else {
    PyErr_SetString(hof_error_type, text.c_str());
  }
  throw py::error_already_set();
}

template <class T>
T value_or_raise(Expected<T> result) {
  if (!result) raise(result.error());
  return std::move(*result);
}

inline void ok_or_raise(const Expected<void>& result) {
  if (!result) raise(result.error());
}

// A Python exception fetched on one side of a released GIL, restored on the other.
class PendingPythonError {
 public:
  PendingPythonError() = default;
  PendingPythonError(const PendingPythonError&) = delete;
  PendingPythonError& operator=(const PendingPythonError&) = delete;
  ~PendingPythonError() {
    if (set()) {
      py::gil_scoped_acquire gil;
      Py_XDECREF(type_);
      Py_XDECREF(value_);
      Py_XDECREF(traceback_);
    }
  }
  /// Takes the current Python error (GIL held). The first one is kept.
  void fetch() {
    if (set()) {
      PyErr_Clear();
      return;
    }
    PyErr_Fetch(&type_, &value_, &traceback_);
  }
  [[nodiscard]] bool set() const { return type_ != nullptr; }
  /// Raises it (GIL held).
  [[noreturn]] void raise() {
    PyErr_Restore(type_, value_, traceback_);
    type_ = value_ = traceback_ = nullptr;
    throw py::error_already_set();
  }

 private:
  PyObject* type_{nullptr};
  PyObject* value_{nullptr};
  PyObject* traceback_{nullptr};
};

// ---- arrays -------------------------------------------------------------------------------

py::array_t<double> points_array(std::span<const Vec3> points) {
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) view(static_cast<py::ssize_t>(i), k) = points[i][k];
  }
  return out;
}

py::array_t<double> flat_points_array(const Eigen::VectorXd& flat) {
  const auto n = static_cast<py::ssize_t>(flat.size() / 3);
  py::array_t<double> out({n, py::ssize_t{3}});
  std::copy(flat.data(), flat.data() + 3 * n, out.mutable_data());
  return out;
}

py::array_t<double> vec3_array(const Vec3& v) {
  py::array_t<double> out(3);
  std::copy(v.data(), v.data() + 3, out.mutable_data());
  return out;
}

template <std::size_t K>
py::array_t<std::int32_t> index_array(const std::vector<std::array<std::int32_t, K>>& items) {
  py::array_t<std::int32_t> out({static_cast<py::ssize_t>(items.size()), static_cast<py::ssize_t>(K)});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < items.size(); ++i) {
    for (std::size_t k = 0; k < K; ++k) view(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(k)) = items[i][k];
  }
  return out;
}

// An (n, 3) float64 array from Python (any object numpy can read as one: a list, an array of
// another float type is converted; a wrong shape or non-numbers are refused by name).
std::vector<Vec3> points_from(const py::handle& object, const char* what) {
  py::array_t<double, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
  } catch (const py::error_already_set&) {
    a = {};
  }
  if (!a || a.ndim() != 2 || a.shape(1) != 3) {
    const std::string shape = a ? fmt::format("an array of shape {}", py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim())))).cast<std::string>())
                                : std::string("not an array of numbers");
    throw py::value_error(fmt::format("{} must be an (n, 3) array of float64 coordinates in metres, got {}", what, shape));
  }
  std::vector<Vec3> out(static_cast<std::size_t>(a.shape(0)));
  auto view = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    out[static_cast<std::size_t>(i)] = Vec3(view(i, 0), view(i, 1), view(i, 2));
    if (!out[static_cast<std::size_t>(i)].allFinite()) throw py::value_error(fmt::format("{}: row {} is not finite", what, i));
  }
  return out;
}

// An (m, K) integer array of indices into `count` items; a float array or a negative or too
// large index is refused by name (never read out of bounds).
template <std::size_t K>
std::vector<std::array<std::int32_t, K>> indices_from(const py::handle& object, const char* what, std::size_t count) {
  py::array a = py::array::ensure(object);
  if (!a || !(a.dtype().kind() == 'i' || a.dtype().kind() == 'u') || a.ndim() != 2 || a.shape(1) != static_cast<py::ssize_t>(K)) {
    throw py::value_error(fmt::format("{} must be an (m, {}) array of integer node indices (int32)", what, K));
  }
  auto ints = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
  auto view = ints.template unchecked<2>();
  std::vector<std::array<std::int32_t, K>> out(static_cast<std::size_t>(a.shape(0)));
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    for (std::size_t k = 0; k < K; ++k) {
      const std::int64_t v = view(i, static_cast<py::ssize_t>(k));
      if (v < 0 || static_cast<std::uint64_t>(v) >= count) {
        throw py::index_error(fmt::format("{}: row {} names node {}, but there are {} nodes", what, i, v, count));
      }
      out[static_cast<std::size_t>(i)][k] = static_cast<std::int32_t>(v);
    }
  }
  return out;
}

// ---- meshes -------------------------------------------------------------------------------

struct PyMesh {
  mesh::Mesh mesh;
  std::vector<std::string> warnings;
  std::string format;
};

PyMesh mesh_from_arrays(const py::object& nodes, const py::object& tets, const py::object& triangles) {
  PyMesh m;
  m.mesh.nodes = points_from(nodes, "nodes");
  if (!tets.is_none()) m.mesh.tets = indices_from<4>(tets, "tets", m.mesh.nodes.size());
  if (!triangles.is_none()) m.mesh.triangles = indices_from<3>(triangles, "triangles", m.mesh.nodes.size());
  return m;
}

py::dict mesh_info(const PyMesh& m) {
  const mesh::MeshReport r = mesh::make_mesh_report(m.mesh);
  py::dict d;
  d["nodes"] = r.nodes;
  d["tets"] = r.tets;
  d["file_triangles"] = r.file_triangles;
  d["edges"] = r.edges;
  d["surface_triangles"] = r.surface_triangles;
  d["surface_vertices"] = r.surface_vertices;
  d["unused_nodes"] = r.unused_nodes;
  d["bbox_min"] = vec3_array(r.bbox_min);
  d["bbox_max"] = vec3_array(r.bbox_max);
  d["volume_m3"] = r.volume_m3;
  if (r.tets > 0) {
    py::dict q;
    q["min_dihedral_deg"] = r.quality.min_dihedral_deg;
    q["max_dihedral_deg"] = r.quality.max_dihedral_deg;
    q["mean_min_dihedral_deg"] = r.quality.mean_min_dihedral_deg;
    q["min_radius_ratio"] = r.quality.min_radius_ratio;
    q["mean_radius_ratio"] = r.quality.mean_radius_ratio;
    q["min_volume_m3"] = r.quality.min_volume_m3;
    q["max_volume_m3"] = r.quality.max_volume_m3;
    q["inverted"] = r.quality.inverted;
    q["degenerate"] = r.quality.degenerate;
    d["quality"] = q;
  }
  d["closed"] = r.surface.closed_manifold();
  d["problems"] = r.problems;
  if (!m.format.empty()) d["format"] = m.format;
  d["warnings"] = m.warnings;
  return d;
}

// ---- devices ------------------------------------------------------------------------------

// A Python function t -> (x, y, z) as a device (virtual time only: it is called on the
// caller's thread with the GIL taken again). Positions are in the world frame, metres; the
// velocity is the difference of the last two positions. An exception, a NaN or a value that
// is not three numbers ends the run: the device reports no reading from then on (the force
// fades to zero) and the run raises the error.
class FunctionDevice final : public haptics::Device {
 public:
  FunctionDevice(py::function function, PendingPythonError& error, coupling::Session*& session)
      : function_(std::move(function)), error_(error), session_(session) {}
  ~FunctionDevice() override {
    py::gil_scoped_acquire gil;
    function_ = py::function();
  }
  [[nodiscard]] const haptics::DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "python-function"; }
  haptics::DeviceReading read(double time_s) override {
    haptics::DeviceReading r;
    r.time_s = time_s;
    if (failed_) return r;
    py::gil_scoped_acquire gil;
    try {
      const py::object value = function_(time_s);
      const auto numbers = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
      if (!numbers || numbers.size() != 3) {
        throw py::value_error(fmt::format("the device function must return a position (x, y, z) in metres, got {}",
                                          py::repr(value).cast<std::string>()));
      }
      r.position_m = Vec3(numbers.data()[0], numbers.data()[1], numbers.data()[2]);
      if (!r.position_m.allFinite()) {
        throw py::value_error(fmt::format("the device function returned {} at t = {} s: not finite", py::repr(value).cast<std::string>(), time_s));
      }
    } catch (py::error_already_set& e) {
      e.restore();
      fail();
      return r;
    } catch (py::builtin_exception& e) {
      e.set_error();
      fail();
      return r;
    }
    r.velocity_m_per_s = has_last_ && time_s > last_time_ ? Vec3((r.position_m - last_) / (time_s - last_time_)) : Vec3::Zero();
    last_ = r.position_m;
    last_time_ = time_s;
    has_last_ = true;
    r.valid = true;
    return r;
  }
  void write_force(const Vec3&, const Vec3&) override {}
  [[nodiscard]] haptics::DeviceHealth health() const override {
    return failed_ ? haptics::DeviceHealth::kFailed : haptics::DeviceHealth::kOk;
  }

 private:
  void fail() {
    error_.fetch();
    failed_ = true;
    if (session_) session_->request_stop();
  }
  py::function function_;
  PendingPythonError& error_;
  coupling::Session*& session_;
  haptics::DeviceSpec spec_;
  Vec3 last_{Vec3::Zero()};
  double last_time_{0.0};
  bool has_last_{false};
  bool failed_{false};
};

// ---- worlds -------------------------------------------------------------------------------

struct Telemetry {
  std::vector<app::TelemetryRow> rows;
};

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

  static std::unique_ptr<PyWorld> load(const std::filesystem::path& path, const std::string& device) {
    Expected<scene::World> world = [&] {
      py::gil_scoped_release release;
      return scene::build_world(path, device);
    }();
    if (!world) raise(world.error());
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
    auto session = coupling::Session::make(std::move(world.bodies), std::move(*device), config);
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
      throw py::index_error(fmt::format("body index {} is out of range: this world has {} bod{}", i, n, n == 1 ? "y" : "ies"));
    }
    return static_cast<std::size_t>(at);
  }
  const coupling::SessionBody& deformable(const py::object& body, std::size_t* index = nullptr) const {
    const std::size_t i = body_index(body);
    if (index) *index = i;
    const coupling::SessionBody& b = session_->body(i);
    if (!b.deformable()) throw py::value_error(fmt::format("body '{}' is a rigid shape: it has no nodes (use surface())", b.name));
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
  py::array_t<double> rest_positions(const py::object& body) const { return points_array(deformable(body).model->rest_positions); }
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
    return target == "haptics" || target.starts_with("haptics/") || target == "graphics" || target.starts_with("graphics/");
  }
  void set(const std::string& target, const std::string& parameter, const py::object& value) {
    if (project_setting(target)) return set_project(target, parameter, value);
    if (!py::isinstance<py::float_>(value) && !py::isinstance<py::int_>(value)) {
      throw py::type_error(fmt::format("{} {}: a mechanics parameter is a number, got {}", target, parameter,
                                       py::repr(value).cast<std::string>()));
    }
    const auto [body, component] = split_target(target);
    ok_or_raise(session_->submit(coupling::command::SetParameter{body, component, parameter, value.cast<double>()}));
  }
  // A setting of the project file (the window's panels): checked as when the file is read,
  // carried to the session by the commands the window sends, kept for save().
  void set_project(const std::string& element, const std::string& attribute, const py::object& value) {
    std::string text;
    if (py::isinstance<py::bool_>(value)) text = value.cast<bool>() ? "true" : "false";
    else if (py::isinstance<py::str>(value)) text = value.cast<std::string>();
    else if (py::isinstance<py::float_>(value) || py::isinstance<py::int_>(value)) text = py::repr(value).cast<std::string>();
    else throw py::type_error(fmt::format("{}@{}: a setting is a number, a bool or a string", element, attribute));
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
    for (const coupling::Command& c : commands.value_or(std::vector<coupling::Command>{})) ok_or_raise(session_->submit(c));
    world_->project = std::move(next);
    if (!commands) {
      PyErr_WarnEx(PyExc_UserWarning,
                   fmt::format("{}@{} is saved with the project; it takes effect when the project is loaded again", element, attribute).c_str(),
                   1);
    }
  }
  double get(const std::string& target, const std::string& parameter) const {
    const auto [body, component] = split_target(target);
    return value_or_raise(session_->parameter(body, component, parameter));
  }
  std::vector<std::string> parameters(const py::object& body) const {
    const coupling::SessionBody& b = deformable(body);
    std::vector<std::string> names;
    if (b.config) {
      for (const std::string& n : mechanics::parameter_names(*b.config)) names.push_back(b.name + "/" + n);
    }
    return names;
  }
  void set_force_limit(double newtons) { ok_or_raise(session_->submit(coupling::command::SetForceLimit{newtons})); }

  void save(const std::filesystem::path& path) {
    if (world_->file.extension() == ".x3d") {
      raise(Error{ErrorCode::kUnsupported, "an X3D scene cannot be saved as a project yet (the project format holds SOFA scenes)",
                  path.string(), 0, -1});
    }
    scene::HofProject out = scene::moved_project(world_->project, world_->file, path);
    if (world_->default_probe) out.device = "auto";  // the probe is fitted again when it is read
    scene::record_changes(out, *session_);
    // And those accepted but not applied yet (no step since they were set).
    scene::record_parameters(out, session_->parameter_changes(/*with_queued=*/true));
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
      throw py::value_error(fmt::format("telemetry_rate must be in [0, 100000] rows/s (0 = every tick), got {}", telemetry_rate));
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
    return py::make_tuple(json.attr("loads")(summary), columns(recording, telemetry));
  }

 private:
  void switch_device(const py::object& device, bool deterministic) {
    coupling::command::SetDevice command;
    if (py::isinstance<py::str>(device)) {
      command.spec = device.cast<std::string>();
      device_spec_ = command.spec;
    } else if (PyCallable_Check(device.ptr())) {
      if (!deterministic) {
        throw py::value_error("a Python function as the device runs in virtual time only (deterministic=True): in real time it "
                              "would hold the haptic thread to the interpreter");
      }
      command.spec = "python-function";
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
      report = deterministic ? session_->run_virtual(seconds, record, progress) : session_->run_realtime(seconds, record, progress);
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

  // The telemetry as columns named as telemetry.csv's: float64 arrays, `contact` bool,
  // `press` int32, `body` (and a needle's `phase`) str arrays.
  py::dict columns(const app::RunRecording& recording, const Telemetry& telemetry) const {
    const auto n = static_cast<py::ssize_t>(telemetry.rows.size());
    py::dict d;
    const auto number = [&](const char* name, auto get) {
      py::array_t<double> a(n);
      double* p = a.mutable_data();
      for (py::ssize_t i = 0; i < n; ++i) p[i] = get(telemetry.rows[static_cast<std::size_t>(i)]);
      d[name] = a;
    };
    using Row = app::TelemetryRow;
    number("t", [](const Row& r) { return r.time_s; });
    number("device_x", [](const Row& r) { return r.device.x(); });
    number("device_y", [](const Row& r) { return r.device.y(); });
    number("device_z", [](const Row& r) { return r.device.z(); });
    number("proxy_x", [](const Row& r) { return r.proxy.x(); });
    number("proxy_y", [](const Row& r) { return r.proxy.y(); });
    number("proxy_z", [](const Row& r) { return r.proxy.z(); });
    number("force_x", [](const Row& r) { return r.force.x(); });
    number("force_y", [](const Row& r) { return r.force.y(); });
    number("force_z", [](const Row& r) { return r.force.z(); });
    {
      py::array_t<bool> a(n);
      for (py::ssize_t i = 0; i < n; ++i) a.mutable_data()[i] = telemetry.rows[static_cast<std::size_t>(i)].contact;
      d["contact"] = a;
    }
    number("penetration", [](const Row& r) { return r.penetration_m; });
    number("period", [](const Row& r) { return r.period_s; });
    number("indentation", [](const Row& r) { return r.indentation_m; });
    py::list bodies;
    for (const Row& r : telemetry.rows) bodies.append(r.body >= 0 ? session_->body(static_cast<std::size_t>(r.body)).name : std::string());
    d["body"] = py::module_::import("numpy").attr("array")(bodies, "str");
    if (recording.needle_mounted()) {
      number("depth", [](const Row& r) { return r.needle_depth_m; });
      py::list phases;
      for (const Row& r : telemetry.rows) phases.append(std::string(procedures::phase_name(static_cast<procedures::NeedlePhase>(r.needle_phase))));
      d["phase"] = py::module_::import("numpy").attr("array")(phases, "str");
      number("needle_force", [](const Row& r) { return r.needle_force_n; });
      number("sent_axial_force", [](const Row& r) { return r.sent_axial_force_n; });
    }
    py::array_t<std::int32_t> press(n);
    for (py::ssize_t i = 0; i < n; ++i) press.mutable_data()[i] = telemetry.rows[static_cast<std::size_t>(i)].press;
    d["press"] = press;
    return d;
  }

  // The report folder `hof run --out` writes: telemetry.csv, summary.json, the shapes, the plots.
  void write_report(const std::filesystem::path& dir, const app::RunRecording& recording, const coupling::SessionReport& report,
                    const std::string& summary, const Telemetry& telemetry, bool quiet) const {
    py::gil_scoped_release release;
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    std::string csv = recording.csv_header();
    for (const app::TelemetryRow& row : telemetry.rows) csv += recording.csv_row(row);
    Expected<void> written = write_file_atomically(dir / "telemetry.csv", csv);
    if (written) written = write_file_atomically(dir / "summary.json", summary);
    if (written) recording.write_report_files(dir, report, quiet);
    if (!written) {
      py::gil_scoped_acquire gil;
      raise(written.error());
    }
  }

  std::unique_ptr<scene::World> world_;  // its bodies are the session's
  std::unique_ptr<coupling::Session> session_;
  coupling::Session* running_{nullptr};  // the session while a run is going (a device may stop it)
  PendingPythonError device_error_;
  std::string device_spec_;
  std::optional<haptics::HapticSample> last_sample_;
};

}  // namespace
}  // namespace hof::python

using namespace hof;
using namespace hof::python;

PYBIND11_MODULE(_hof, module) {
  module.doc() = "HoF (Haptics Open Framework): deformable worlds, haptic sessions and meshes. See docs/python.md.";
  static py::exception<std::runtime_error> error_type(module, "Error", PyExc_RuntimeError);
  hof_error_type = error_type.ptr();

  py::class_<PyWorld>(module, "World", "A world of bodies and its haptic session (hof.load() makes one).")
      .def_static("load", &PyWorld::load, py::arg("path"), py::arg("device") = "",
                  "Builds the world of a .hof project, SOFA .scn or X3D scene (the builder `hof run` uses). `device` "
                  "replaces the file's device (a spec string, as --device).")
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
      .def("run", &PyWorld::run, py::arg("seconds") = py::none(), py::arg("device") = py::none(), py::arg("deterministic") = true,
           py::arg("telemetry_rate") = 0.0, py::arg("out") = py::none(), py::arg("quiet") = true,
           "Runs a haptic session (as `hof run`); returns (report, telemetry): summary.json as a dict and the telemetry "
           "columns as numpy arrays.")
      .def("positions", &PyWorld::positions, py::arg("body") = 0, "(n, 3) node positions, m (a copy).")
      .def("velocities", &PyWorld::velocities, py::arg("body") = 0, "(n, 3) node velocities, m/s (a copy).")
      .def("forces", &PyWorld::forces, py::arg("body") = 0, "(n, 3) total force on each node at the last step, N (a copy).")
      .def("rest_positions", &PyWorld::rest_positions, py::arg("body") = 0, "(n, 3) rest positions, m (a copy).")
      .def("tets", &PyWorld::tets, py::arg("body") = 0, "(m, 4) int32 tetrahedra (a copy).")
      .def("masses", &PyWorld::masses, py::arg("body") = 0, "(n,) lumped node masses, kg (a copy).")
      .def("fixed_nodes", &PyWorld::fixed_nodes, py::arg("body") = 0, "Nodes held on at least one axis.")
      .def("surface", &PyWorld::surface, py::arg("body") = 0,
           "(vertices (v, 3) m, triangles (f, 3) int32): the touchable surface as it is now (copies).")
      .def("normals", &PyWorld::normals, py::arg("body") = 0, "(v, 3) unit vertex normals of the surface as it is now.")
      .def("contact", &PyWorld::contact, "The last haptic tick's contact as a dict (None before any run).")
      .def("set", &PyWorld::set, py::arg("target"), py::arg("parameter"), py::arg("value"),
           "Sets a parameter through the command seam, e.g. set('Liver/FEM', 'youngModulus', 8000), or a setting of the "
           "project by the file's names, e.g. set('haptics/surface', 'stiffness', 0.4), set('haptics', 'renderer', "
           "'GodObjectRenderer'); applied before the next step. Checked now: a bad value raises ValueError with the "
           "command line's message.")
      .def("get", &PyWorld::get, py::arg("target"), py::arg("parameter"), "A parameter's value as the accepted commands leave it.")
      .def("parameters", &PyWorld::parameters, py::arg("body") = 0, "Every 'Body/component/parameter' set() takes for a body.")
      .def("set_force_limit", &PyWorld::set_force_limit, py::arg("newtons"), "A force limit below the device's (0: the device's).")
      .def("save", &PyWorld::save, py::arg("path"), "Writes the world as a .hof project, with the parameters changed so far.");

  py::module_ mesh_module = module.def_submodule("mesh", "Mesh files, reports, meshing and the standard livers.");
  py::class_<PyMesh>(mesh_module, "Mesh", "A mesh: nodes (n, 3) m, tets (m, 4) and triangles (f, 3) int32 (copies).")
      .def(py::init(&mesh_from_arrays), py::arg("nodes"), py::arg("tets") = py::none(), py::arg("triangles") = py::none())
      .def_property_readonly("nodes", [](const PyMesh& m) { return points_array(m.mesh.nodes); })
      .def_property_readonly("tets", [](const PyMesh& m) { return index_array(m.mesh.tets); })
      .def_property_readonly("triangles", [](const PyMesh& m) { return index_array(m.mesh.triangles); })
      .def_property_readonly("warnings", [](const PyMesh& m) { return m.warnings; })
      .def("info", &mesh_info, "The report `hof mesh info` prints, as a dict.")
      .def(
          "write",
          [](const PyMesh& m, const std::filesystem::path& path) {
            Expected<void> ok = [&] {
              py::gil_scoped_release release;
              return mesh::write_mesh(m.mesh, path);
            }();
            ok_or_raise(ok);
          },
          py::arg("path"), "Writes by extension: .msh (Gmsh 4.1), .vtu, .obj, .off.")
      .def("__repr__", [](const PyMesh& m) {
        return fmt::format("<hof.mesh.Mesh: {} nodes, {} tets, {} triangles>", m.mesh.nodes.size(), m.mesh.tets.size(),
                           m.mesh.triangles.size());
      });
  mesh_module.def(
      "read",
      [](const std::filesystem::path& path) {
        Expected<mesh::ReadResult> read = [&] {
          py::gil_scoped_release release;
          return mesh::read_mesh(path);
        }();
        mesh::ReadResult r = value_or_raise(std::move(read));
        return PyMesh{std::move(r.mesh), std::move(r.report.warnings), r.report.format};
      },
      py::arg("path"), "Reads a mesh: Gmsh .msh (v1, v2, v4), .vtu, .obj, .stl, .off.");
  mesh_module.def(
      "generate_liver",
      [](const std::string& resolution) {
        const auto r = mesh::parse_liver_resolution(resolution);
        if (!r) throw py::value_error(fmt::format("unknown liver '{}': simple, coarse, medium or fine", resolution));
        Expected<mesh::Mesh> made = [&] {
          py::gil_scoped_release release;
          return mesh::generate_liver(*r);
        }();
        return PyMesh{value_or_raise(std::move(made)), {}, {}};
      },
      py::arg("resolution") = "medium", "The standard tetrahedral liver: 'simple', 'coarse', 'medium' or 'fine'.");
  mesh_module.def(
      "tetrahedralize",
      [](const PyMesh& surface, double max_volume, double radius_edge_ratio) {
        if (surface.mesh.triangles.empty()) throw py::value_error("tetrahedralize needs a closed triangle surface (the mesh has no triangles)");
        mesh::TetrahedralizeOptions options;
        options.max_volume_m3 = max_volume;
        options.radius_edge_ratio = radius_edge_ratio;
        Expected<mesh::Mesh> made = [&] {
          py::gil_scoped_release release;
          return mesh::tetrahedralize(mesh::TriMesh{surface.mesh.nodes, surface.mesh.triangles}, options);
        }();
        return PyMesh{value_or_raise(std::move(made)), {}, {}};
      },
      py::arg("surface"), py::arg("max_volume") = 0.0, py::arg("radius_edge_ratio") = 1.414,
      "Fills a closed surface with tetrahedra (TetGen): max_volume m^3 (0: unbounded), the radius-edge quality bound.");
}
