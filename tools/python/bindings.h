// What the files of the Python module's compiled part share (module.cpp puts them together): a
// prepared run as Python holds it, frames as dicts of numpy arrays (frame_arrays.cpp), and the
// arguments Recipe and Run both take (helpers.cpp). The frame dict's keys are documented once, in
// cadsynth/_cadsynth.pyi (class Frame).
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <tbb/task_arena.h>

#include "tools/pipeline/frames.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/shards.h"

namespace cadsynth::python {

namespace py = pybind11;

// Each adds its classes or functions to the module. BindRun comes before BindRecipe, so that
// Recipe.prepare's signature names the Python class Run, not the C++ type.
void BindRun(py::module_& m);      // run_bindings.cpp: Run and FrameIterator
void BindRecipe(py::module_& m);   // recipe_bindings.cpp: Recipe
void BindHelpers(py::module_& m);  // helpers.cpp: encode_png, read_image, evaluate, ...

// A prepared run in Python.
struct PyRun {
  std::shared_ptr<const FrameSource> source;
};

// What one frame (one sensor's) becomes in Python: a dict of numpy arrays.
struct FrameOptions {
  bool masks = true;  // N x H x W masks (the instance image is always there)
};

// A rendered view as Python sees it: the first sensor's dict, with every sensor's dict under
// "sensors" for a rig of several.
py::dict ViewDict(RenderedView&& view, const FrameSource& source, const FrameOptions& options);

// The part cache the command line uses by default, or another folder, or none.
std::optional<std::filesystem::path> CacheFolder(const py::object& cache);
// (i, n), "i/n" or None.
std::optional<ShardSpec> ShardOf(const py::object& shard);
GenerateOptions WriteOptions(const std::filesystem::path& output, bool overwrite,
                             const py::object& shard);
py::dict SummaryDict(const GenerateSummary& s);

// A numpy array that owns `values` (moved into it, not copied).
template <class T>
py::array_t<T> Own(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule free(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, owned->data(), free);
}

// Runs `work` with the GIL released, under a thread limit when `threads` > 0.
template <class F>
auto Released(int threads, F&& work) {
  py::gil_scoped_release release;
  if (threads > 0) {
    tbb::task_arena arena(threads);
    return arena.execute(std::forward<F>(work));
  }
  return work();
}

}  // namespace cadsynth::python
