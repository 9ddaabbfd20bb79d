#pragma once
// The parts of the extension module tetcut._tetcut, one function per area of the public API.

#include <pybind11/pybind11.h>

namespace tetcut::python {

void bind_meshes(pybind11::module_& m);   // errors, files, generators, quality (module.cpp)
void bind_cutting(pybind11::module_& m);  // Cutter, its results and reports, embed (cutting.cpp)
void bind_sim(pybind11::module_& m);      // tetcut.sim: Simulator; Session (simulation.cpp)

}  // namespace tetcut::python
