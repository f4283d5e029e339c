#include "hof/python/common.h"

namespace hof::python {

PyObject* hof_error_type = nullptr;

[[noreturn]] void raise(const Error& e) {
  const std::string text = e.to_string();
  if (e.code == ErrorCode::kIo) {
    const bool missing =
        e.message.find("no such file") != std::string::npos || e.message.find("not found") != std::string::npos;
    PyErr_SetString(missing ? PyExc_FileNotFoundError : PyExc_OSError, text.c_str());
  } else if (e.code == ErrorCode::kInvalidArgument) {
    PyErr_SetString(PyExc_ValueError, text.c_str());
  } else {
    PyErr_SetString(hof_error_type, text.c_str());
  }
  throw py::error_already_set();
}

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

std::vector<Vec3> points_from(const py::handle& object, const char* what) {
  py::array_t<double, py::array::c_style | py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(object);
  } catch (const py::error_already_set&) {
    a = {};
  }
  if (!a || a.ndim() != 2 || a.shape(1) != 3) {
    const std::string shape =
        a ? fmt::format("an array of shape {}",
                        py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()))))
                            .cast<std::string>())
          : std::string("not an array of numbers");
    throw py::value_error(
        fmt::format("{} must be an (n, 3) array of float64 coordinates in metres, got {}", what, shape));
  }
  std::vector<Vec3> out(static_cast<std::size_t>(a.shape(0)));
  auto view = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i) {
    out[static_cast<std::size_t>(i)] = Vec3(view(i, 0), view(i, 1), view(i, 2));
    if (!out[static_cast<std::size_t>(i)].allFinite())
      throw py::value_error(fmt::format("{}: row {} is not finite", what, i));
  }
  return out;
}

}  // namespace hof::python
