// Recipe: a run's recipe read and checked, and what it becomes (Recipe.prepare(), Recipe.write()).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>
#include <string>
#include <vector>

#include "recipes/recipe.h"
#include "tools/python/bindings.h"

using namespace pybind11::literals;

namespace cadsynth::python {
namespace {

// The run's recipe as Python holds it: the RunSpec, and what re-reads it in another process
// (pickling, for DataLoader workers started by spawn).
struct PyRecipe {
  RunSpec base;  // as read, with the recipe's own seeds
  RunSpec spec;  // Reseed(base, stream)
  // How it was made: "file" (path), "text" (text, name, base_dir) or "default".
  std::string origin = "default";
  std::string text, name;
  std::filesystem::path base_dir;
  uint64_t stream = 0;
};

PyRecipe FromText(const std::string& text, const std::string& name,
                  const std::filesystem::path& base_dir) {
  PyRecipe r;
  r.base = ParseRecipe(text, name, base_dir);
  r.spec = r.base;
  r.origin = "text";
  r.text = text;
  r.name = name;
  r.base_dir = base_dir;
  return r;
}

PyRecipe FromFile(const std::filesystem::path& path) {
  PyRecipe r;
  r.base = LoadRecipe(path);
  r.spec = r.base;
  r.origin = "file";
  r.name = path.string();
  return r;
}

}  // namespace

void BindRecipe(py::module_& m) {
  py::class_<PyRecipe>(m, "Recipe", R"(A run's recipe (docs/recipes.md), read and checked.

Recipe.load(path), Recipe.from_yaml(text), Recipe.from_dict(dict) or Recipe.default() (the
built-in default job). A bad recipe raises cadsynth.Error "FILE:LINE:COLUMN: what".)")
      .def_static(
          "load", [](const std::filesystem::path& path) { return FromFile(path); }, "path"_a,
          "Reads a recipe file.")
      .def_static(
          "from_yaml",
          [](const std::string& text, const std::string& name,
             const std::filesystem::path& base_dir) { return FromText(text, name, base_dir); },
          "text"_a, "name"_a = "<string>", "base_dir"_a = ".",
          "Reads a recipe from YAML text; relative paths are resolved against base_dir.")
      .def_static(
          "from_dict",
          [](const py::dict& recipe, const std::filesystem::path& base_dir) {
            // YAML is a superset of JSON: the dict as indented JSON is a recipe text whose lines
            // and columns the error messages name.
            const std::string text = py::module_::import("json")
                                         .attr("dumps")(recipe, "indent"_a = 2)
                                         .cast<std::string>();
            return FromText(text, "<dict>", base_dir);
          },
          "recipe"_a, "base_dir"_a = ".",
          "A recipe from a dict of the recipe's keys (as the YAML file would hold them).")
      .def_static(
          "default",
          [] {
            PyRecipe r;
            r.base = DefaultRunSpec();
            r.spec = r.base;
            return r;
          },
          "The built-in default job (what `cadsynth generate` runs without a recipe).")
      .def(
          "reseeded",
          [](const PyRecipe& r, uint64_t stream) {
            PyRecipe out = r;
            out.stream = stream;
            out.spec = Reseed(r.base, stream);
            return out;
          },
          "stream"_a,
          "The recipe with every per-run seed (arrangement, piles, randomisation, views, sampler, "
          "sensor noise) moved to stream `stream` of the recipe's own seeds (0: the recipe "
          "itself; streams do not compound: r.reseeded(1).reseeded(2) is r.reseeded(2)).")
      .def_property_readonly("path",
                             [](const PyRecipe& r) -> py::object {
                               if (r.spec.recipe.empty()) return py::none();
                               return py::cast(r.spec.recipe);
                             })
      .def_property_readonly("stream", [](const PyRecipe& r) { return r.stream; })
      .def_property_readonly("scenes",
                             [](const PyRecipe& r) {
                               std::vector<std::string> names;
                               for (const SceneSpec& s : r.spec.scenes) names.push_back(s.name);
                               return names;
                             })
      .def_property_readonly("views",
                             [](const PyRecipe& r) {
                               return r.spec.sampler.kind == ViewSampler::Kind::kGrid
                                          ? r.spec.sweep.NumViews()
                                          : SampleViews(r.spec.sampler, r.spec.sweep).size();
                             })
      .def(
          "prepare",
          [](const PyRecipe& r, const py::object& cache, int threads, bool verbose,
             bool denoiser_inputs) {
            FrameSourceOptions options;
            options.cache = CacheFolder(cache);
            if (verbose) {
              options.info = [](const std::string& line) {
                py::gil_scoped_acquire acquire;
                py::print(line, "file"_a = py::module_::import("sys").attr("stderr"));
              };
            }
            RunSpec spec = r.spec;
            spec.render.denoiser_inputs = denoiser_inputs;
            PyRun run;
            run.source = Released(
                threads, [&] { return std::make_shared<const FrameSource>(spec, options); });
            return run;
          },
          "cache"_a = true, "threads"_a = 0, "verbose"_a = false, "denoiser_inputs"_a = false,
          R"(Reads and builds the parts, arranges (or drops) every scene and plans the views.

cache: True (the command line's part cache), False/None, or a folder.
threads: at most this many threads (0: all cores).
denoiser_inputs: pbr mode: frames also hold what the denoiser reads (the denoiser_* keys; for
training one, tools/denoiser/).)")
      .def(
          "write",
          [](const PyRecipe& r, const std::filesystem::path& output, bool overwrite,
             const py::object& shard, const py::object& cache, int threads) {
            GenerateOptions options = WriteOptions(output, overwrite, shard);
            options.cache = CacheFolder(cache);
            return SummaryDict(Released(threads, [&] { return Generate(r.spec, options); }));
          },
          "output"_a, "overwrite"_a = false, "shard"_a = py::none(), "cache"_a = true,
          "threads"_a = 0, "Runs the ordinary dataset writer (`cadsynth generate`) into `output`.")
      .def(py::pickle(
          [](const PyRecipe& r) {
            return py::make_tuple(r.origin, r.origin == "file" ? r.name : r.text, r.name,
                                  r.base_dir, r.stream);
          },
          [](const py::tuple& t) {
            const std::string origin = t[0].cast<std::string>();
            PyRecipe r;
            if (origin == "file") {
              r = FromFile(t[1].cast<std::string>());
            } else if (origin == "text") {
              r = FromText(t[1].cast<std::string>(), t[2].cast<std::string>(),
                           t[3].cast<std::filesystem::path>());
            } else {
              r.base = DefaultRunSpec();
            }
            r.stream = t[4].cast<uint64_t>();
            r.spec = Reseed(r.base, r.stream);
            return r;
          }));
}

}  // namespace cadsynth::python
