// The Python module `cadsynth` (its compiled part, cadsynth._cadsynth): recipes, prepared runs and
// their frames as dicts of numpy arrays, over the same pipeline library the command line uses
// (tools/pipeline/frames.h). The pure-Python part (tools/python/cadsynth/) adds the torch dataset;
// cadsynth/_cadsynth.pyi describes this module's API and a frame's keys for editors.
//
// By concern: recipe_bindings.cpp (Recipe), run_bindings.cpp (Run and the frame stream),
// frame_arrays.cpp (a frame as numpy arrays), helpers.cpp (the module's functions).
#include <pybind11/pybind11.h>

#include "cad/core/error.h"
#include "tools/python/bindings.h"

PYBIND11_MODULE(_cadsynth, m) {
  namespace py = pybind11;
  using namespace cadsynth::python;
  m.doc() = "cadsynth: CAD to labelled RGB-D frames (the compiled part; import cadsynth)";
  py::register_exception<cadsynth::Error>(m, "Error", PyExc_RuntimeError);
  BindRun(m);
  BindRecipe(m);
  BindHelpers(m);
  m.attr("__version__") = CADSYNTH_VERSION;
}
