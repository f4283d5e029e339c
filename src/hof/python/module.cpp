// The `hof` Python module (pybind11): worlds loaded by the one builder, stepped and run in
// virtual or real time through the same Session and the same run recording as `hof run`,
// their state as numpy arrays, their settings through the command seam, and the mesh tools.
// docs/python.md is the user's guide; the package's Python part is hof/__init__.py.
//
// Threads: the GIL is released while C++ works (a step, a run, meshing). A run calls back
// into Python only with the GIL taken again: a function device (virtual time only, on the
// caller's thread) and every few steps a look for a pending signal, so that Ctrl-C stops a
// run after its current step and raises KeyboardInterrupt with the world intact.
//
// The parts: common.h (errors, arrays), world.cpp (hof.World), function_device.h (a Python
// function as the device), run_report.cpp (a run's telemetry columns and report folder),
// mesh.cpp (hof.mesh).

#include <pybind11/pybind11.h>

#include <stdexcept>

#include "hof/python/bindings.h"
#include "hof/python/common.h"

PYBIND11_MODULE(_hof, module) {
  namespace py = pybind11;
  module.doc() = "HoF (Haptics Open Framework): deformable worlds, haptic sessions and meshes. See docs/python.md.";
  static py::exception<std::runtime_error> error_type(module, "Error", PyExc_RuntimeError);
  hof::python::hof_error_type = error_type.ptr();
  hof::python::bind_world(module);
  hof::python::bind_mesh(module);
}
