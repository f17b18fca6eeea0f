// Run (a prepared run: Recipe.prepare()) and its frames, rendered ahead in the background and
// handed to Python in order (FrameIterator).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <condition_variable>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "tools/python/bindings.h"

using namespace pybind11::literals;

namespace cadsynth::python {
namespace {

// Frames rendered ahead in a background thread (a TBB pipeline, frames in flight in parallel)
// and handed over in order; the GIL is released while Python waits.
class FrameStream {
 public:
  FrameStream(std::shared_ptr<const FrameSource> source, std::vector<size_t> units,
              bool skip_unkept, int threads, FrameOptions options)
      : source_(std::move(source)),
        units_(std::move(units)),
        skip_(skip_unkept),
        options_(options),
        threads_(threads > 0 ? threads : tbb::this_task_arena::max_concurrency()) {
    worker_ = std::thread([this] { Run(); });
  }
  ~FrameStream() {
    // Dropped by Python (the GIL held): frames in flight finish without holding up other threads.
    if (PyGILState_Check() != 0) {
      py::gil_scoped_release release;
      Close();
    } else {
      Close();
    }
  }

  // The next frame, or nullopt at the end. Throws the render's Error.
  std::optional<RenderedView> Next() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      ready_.wait(lock, [&] { return !queue_.empty() || finished_; });
      if (!queue_.empty()) {
        RenderedView view = std::move(queue_.front());
        queue_.pop_front();
        space_.notify_all();
        if (skip_ && !view.kept) continue;
        return view;
      }
      if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
      return std::nullopt;
    }
  }

  void Close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
      space_.notify_all();
    }
    if (worker_.joinable()) worker_.join();
  }

  const FrameSource& source() const { return *source_; }
  const FrameOptions& options() const { return options_; }
  size_t units() const { return units_.size(); }

 private:
  void Run() {
    try {
      tbb::task_arena arena(threads_);
      arena.execute([&] {
        size_t next = 0, last_scene = SIZE_MAX;
        tbb::parallel_pipeline(
            2 * static_cast<size_t>(threads_),
            tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                           [&](tbb::flow_control& control) -> size_t {
                                             {
                                               std::lock_guard<std::mutex> lock(mutex_);
                                               if (stop_ || next >= units_.size()) {
                                                 control.stop();
                                                 return 0;
                                               }
                                             }
                                             return units_[next++];
                                           }) &
                tbb::make_filter<size_t, std::shared_ptr<RenderedView>>(
                    tbb::filter_mode::parallel,
                    [&](size_t unit) {
                      auto view = std::make_shared<RenderedView>(source_->Render(unit));
                      // The scene's grasps placed here, once, not later under the GIL.
                      if (source_->spec().grasps.enabled) source_->PlacedGrasps(view->scene);
                      return view;
                    }) &
                tbb::make_filter<std::shared_ptr<RenderedView>, void>(
                    tbb::filter_mode::serial_in_order,
                    [&](const std::shared_ptr<RenderedView>& view) {
                      // Units come in increasing order: once a later scene's frame is out,
                      // no frame of the earlier scene is left to render, and its renderer goes.
                      if (last_scene != SIZE_MAX && view->scene != last_scene)
                        source_->ReleaseScene(last_scene);
                      last_scene = view->scene;
                      std::unique_lock<std::mutex> lock(mutex_);
                      space_.wait(lock, [&] { return stop_ || queue_.size() < Capacity(); });
                      if (stop_) return;
                      queue_.push_back(std::move(*view));
                      ready_.notify_all();
                    }));
      });
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
    ready_.notify_all();
  }
  size_t Capacity() const { return static_cast<size_t>(threads_) + 1; }

  std::shared_ptr<const FrameSource> source_;
  std::vector<size_t> units_;
  bool skip_;
  FrameOptions options_;
  int threads_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  std::deque<RenderedView> queue_;
  bool stop_ = false, finished_ = false;
  std::exception_ptr error_;
  std::thread worker_;
};

}  // namespace

void BindRun(py::module_& m) {
  py::class_<FrameStream>(m, "FrameIterator",
                          "Frames rendered ahead in the background, in order (Run.frames).")
      .def("__iter__", [](FrameStream& s) -> FrameStream& { return s; })
      .def("__next__",
           [](FrameStream& s) {
             std::optional<RenderedView> view;
             {
               py::gil_scoped_release release;
               view = s.Next();
             }
             if (!view) throw py::stop_iteration();
             return ViewDict(std::move(*view), s.source(), s.options());
           })
      .def("__len__", &FrameStream::units,
           "work units of the stream (frames, unless views see too little: min_visible_pixels)")
      .def(
          "close",
          [](FrameStream& s) {
            py::gil_scoped_release release;
            s.Close();
          },
          "Stops rendering ahead.");

  py::class_<PyRun>(m, "Run", "A prepared run: Recipe.prepare().")
      .def_property_readonly("scenes", [](const PyRun& r) { return r.source->scenes(); })
      .def_property_readonly("views", [](const PyRun& r) { return r.source->views().size(); })
      .def_property_readonly(
          "units", [](const PyRun& r) { return r.source->units(); },
          "scenes x views: the work units shards divide")
      .def_property_readonly(
          "objects",
          [](const PyRun& r) {
            py::list out;
            const PreparedRun& p = r.source->prepared();
            for (size_t i = 0; i < p.parts.size(); ++i) {
              out.append(py::dict("obj_id"_a = i + 1, "name"_a = p.parts[i].name,
                                  "class"_a = p.classes[i].name, "class_id"_a = p.classes[i].id));
            }
            return out;
          },
          "The objects (BOP obj_id i + 1 for entry i) and their classes.")
      .def(
          "fixtures",
          [](const PyRun& r, size_t scene) {
            const PreparedRun& p = r.source->prepared();
            if (scene >= p.scenes.size()) {
              throw py::index_error("scene " + std::to_string(scene) + " of " +
                                    std::to_string(p.scenes.size()));
            }
            py::list out;
            for (const Scene::Fixture& f : p.scenes[scene].fixtures) {
              const Mesh& mesh = f.mesh;
              const auto n = static_cast<py::ssize_t>(mesh.num_vertices());
              const auto t = static_cast<py::ssize_t>(mesh.num_triangles());
              const bool has_normals = mesh.normals.size() == mesh.positions.size();
              py::array_t<float> vertices({n, py::ssize_t{3}});
              py::array_t<float> normals({has_normals ? n : py::ssize_t{0}, py::ssize_t{3}});
              py::array_t<uint32_t> triangles({t, py::ssize_t{3}});
              auto v = vertices.mutable_unchecked<2>();
              auto nn = normals.mutable_unchecked<2>();
              auto tt = triangles.mutable_unchecked<2>();
              for (py::ssize_t i = 0; i < n; ++i) {
                for (int c = 0; c < 3; ++c) {
                  v(i, c) = mesh.positions[i][c];
                  if (has_normals) nn(i, c) = mesh.normals[i][c];
                }
              }
              for (py::ssize_t i = 0; i < t; ++i) {
                for (int c = 0; c < 3; ++c) tt(i, c) = mesh.triangles[i][c];
              }
              const PrincipledParams& m = f.material.surface;
              py::dict material(
                  "base_color"_a =
                      std::vector<float>{m.base_color[0], m.base_color[1], m.base_color[2]},
                  "metallic"_a = m.metallic, "roughness"_a = m.roughness, "specular"_a = m.specular,
                  "anisotropic"_a = m.anisotropic, "clearcoat"_a = m.clearcoat,
                  "clearcoat_roughness"_a = m.clearcoat_roughness,
                  "multiscatter"_a = m.multiscatter,
                  "textured"_a = f.material.texture.kind != Texture::Kind::kNone);
              out.append(py::dict("name"_a = f.name, "vertices"_a = vertices, "normals"_a = normals,
                                  "triangles"_a = triangles, "material"_a = material));
            }
            return out;
          },
          "scene"_a,
          R"(Scene `scene`'s fixtures (a pile's tote or container: geometry that is drawn but is
no object), as traced: name, vertices (N x 3 float32, mm, world frame), normals (N x 3, or 0 x 3
when the mesh has none), triangles (M x 3 uint32) and the pbr mode's material before any
randomisation (linear base_color, metallic, roughness, specular, anisotropic, clearcoat,
clearcoat_roughness, multiscatter; textured: whether a texture varies it). For rebuilding a frame in another renderer (tools/cycles).)")
      .def_property_readonly("sensors",
                             [](const PyRun& r) {
                               std::vector<std::string> names;
                               for (const RigSensor& s : r.source->sensors())
                                 names.push_back(s.name);
                               return names;
                             })
      .def(
          "frames",
          [](const PyRun& r, const py::object& shard, bool masks, bool skip, int threads) {
            const std::optional<ShardSpec> spec = ShardOf(shard);
            std::vector<size_t> units;
            for (size_t g = 0; g < r.source->units(); ++g) {
              if (!spec || spec->Owns(g)) units.push_back(g);
            }
            return std::make_unique<FrameStream>(r.source, std::move(units), skip, threads,
                                                 FrameOptions{masks});
          },
          "shard"_a = py::none(), "masks"_a = true, "skip"_a = true, "threads"_a = 0,
          R"(Iterates over the run's frames (in unit order: scene-major, then view), each a dict
of numpy arrays (its keys: class Frame in cadsynth/_cadsynth.pyi).

shard: (i, n) or "i/n": only the units g with g % n == i (as `generate --shard`).
masks: False leaves out the N x H x W masks.
skip: leave out views that show too little (min_visible_pixels), as the writer does.
threads: at most this many threads render (0: all cores).)")
      .def(
          "frame",
          [](const PyRun& r, size_t unit, bool masks) {
            RenderedView view;
            {
              py::gil_scoped_release release;
              view = r.source->Render(unit);
            }
            const bool kept = view.kept;
            py::dict d = ViewDict(std::move(view), *r.source, FrameOptions{masks});
            d["kept"] = kept;
            return d;
          },
          "unit"_a, "masks"_a = true,
          "Renders one work unit (scene * views + view); 'kept' says whether the writer keeps it.")
      .def(
          "write",
          [](const PyRun& r, const std::filesystem::path& output, bool overwrite,
             const py::object& shard, int threads) {
            const GenerateOptions options = WriteOptions(output, overwrite, shard);
            return SummaryDict(Released(threads, [&] { return Generate(*r.source, options); }));
          },
          "output"_a, "overwrite"_a = false, "shard"_a = py::none(), "threads"_a = 0,
          "Writes the prepared run as `cadsynth generate` does (the same files).");
}

}  // namespace cadsynth::python
