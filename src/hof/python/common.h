#pragma once
// What every part of the `hof` Python module shares (internal to the module): errors as
// Python exceptions, a Python error kept across a released GIL, and numpy arrays from and to
// HoF's types.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <fmt/format.h>

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "hof/core/error.h"
#include "hof/core/types.h"

namespace hof::python {

namespace py = pybind11;

// ---- errors -------------------------------------------------------------------------------

/// hof.Error (a RuntimeError), set at import.
extern PyObject* hof_error_type;

/// An Error as a Python exception with the message the command line prints: a missing file is
/// FileNotFoundError, another I/O failure OSError, a value out of range ValueError, the rest
/// hof.Error.
[[noreturn]] void raise(const Error& e);

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

/// (n, 3) float64 copies of points, of a flat [x0 y0 z0 x1 ...] vector, and (3,) of one vector.
py::array_t<double> points_array(std::span<const Vec3> points);
py::array_t<double> flat_points_array(const Eigen::VectorXd& flat);
py::array_t<double> vec3_array(const Vec3& v);

template <std::size_t K>
py::array_t<std::int32_t> index_array(const std::vector<std::array<std::int32_t, K>>& items) {
  py::array_t<std::int32_t> out({static_cast<py::ssize_t>(items.size()), static_cast<py::ssize_t>(K)});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t i = 0; i < items.size(); ++i) {
    for (std::size_t k = 0; k < K; ++k) view(static_cast<py::ssize_t>(i), static_cast<py::ssize_t>(k)) = items[i][k];
  }
  return out;
}

/// An (n, 3) float64 array from Python (any object numpy can read as one: a list, an array of
/// another float type is converted; a wrong shape or non-numbers are refused by name).
std::vector<Vec3> points_from(const py::handle& object, const char* what);

// An (m, K) integer array of indices into `count` items; a float array or a negative or too
// large index is refused by name (never read out of bounds).
template <std::size_t K>
std::vector<std::array<std::int32_t, K>> indices_from(const py::handle& object, const char* what, std::size_t count) {
  py::array a = py::array::ensure(object);
  if (!a || !(a.dtype().kind() == 'i' || a.dtype().kind() == 'u') || a.ndim() != 2 ||
      a.shape(1) != static_cast<py::ssize_t>(K)) {
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

}  // namespace hof::python
