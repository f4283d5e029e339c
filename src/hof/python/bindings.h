#pragma once
// The parts of the `hof` Python module, each adding its classes and functions to the module
// (module.cpp calls them at import).

#include <pybind11/pybind11.h>

namespace hof::python {

/// hof.World (world.cpp).
void bind_world(pybind11::module_& module);
/// The hof.mesh submodule (mesh.cpp).
void bind_mesh(pybind11::module_& module);

}  // namespace hof::python
