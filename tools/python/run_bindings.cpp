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
#include <string>
#include <thread>
#include <type_traits>

#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "cad/core/schema.h"
#include "tools/python/bindings.h"

using namespace pybind11::literals;

namespace cadsynth::python {
namespace {

// A described struct's fields (its static Fields) as a dict under their recipe keys (or internal
// names), in the struct's units: lengths in mm, angles in radians, colours linear; choices by
// name; vectors as lists.
template <class T>
py::object FieldValue(const T& value, const Field& field) {
  if constexpr (std::is_enum_v<T>) {
    return py::str(FieldText(value, field));
  } else if constexpr (std::is_same_v<T, bool>) {
    if (field.choices.size() == 2) return py::str(FieldText(value, field));
    return py::bool_(value);
  } else if constexpr (IsFixedVector<T>::value) {
    py::list list;
    for (int i = 0; i < value.size(); ++i) list.append(static_cast<double>(value[i]));
    return list;
  } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
    return py::str(value.string());
  } else if constexpr (std::is_floating_point_v<T>) {
    return py::float_(static_cast<double>(value));
  } else if constexpr (std::is_integral_v<T>) {
    return py::int_(value);
  } else {
    return py::str(FieldText(value, field));
  }
}

template <class S>
py::dict FieldsDict(const S& options) {
  py::dict out;
  S::Fields(options, [&](const auto& value, const Field& field) {
    out[py::str(std::string(field.Name()))] = FieldValue(value, field);
  });
  return out;
}

// A pbr material: the surface's fields (PrincipledParams: base_color linear, metallic, ...,
// distribution), multiscatter (bool), tangent, base_from_part, textured and texture (Texture's
// fields, scale in mm; None without one).
py::dict MaterialDict(const Material& material) {
  py::dict out = FieldsDict(material.surface);
  out["multiscatter"] = material.surface.multiscatter;
  for (const auto& [key, value] : FieldsDict(material)) out[key] = value;
  const bool textured = material.texture.kind != Texture::Kind::kNone;
  out["textured"] = textured;
  out["texture"] = textured ? py::object(FieldsDict(material.texture)) : py::object(py::none());
  return out;
}

// Prepared scene `scene` of the run, or IndexError.
const Scene& SceneOf(const PyRun& r, size_t scene) {
  const PreparedRun& p = r.source->prepared();
  if (scene >= p.scenes.size()) {
    throw py::index_error("scene " + std::to_string(scene) + " of " +
                          std::to_string(p.scenes.size()));
  }
  return p.scenes[scene];
}

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
            py::list out;
            for (const Scene::Fixture& f : SceneOf(r, scene).fixtures) {
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
              out.append(py::dict("name"_a = f.name, "vertices"_a = vertices, "normals"_a = normals,
                                  "triangles"_a = triangles,
                                  "material"_a = MaterialDict(f.material)));
            }
            return out;
          },
          "scene"_a,
          R"(Scene `scene`'s fixtures (a pile's tote or container: geometry that is drawn but is
no object), as traced: name, vertices (N x 3 float32, mm, world frame), normals (N x 3, or 0 x 3
when the mesh has none), triangles (M x 3 uint32) and the pbr mode's material before any
randomisation (as Run.look's). For rebuilding a frame in another renderer (tools/cycles).)")
      .def(
          "look",
          [](const PyRun& r, size_t scene) {
            const Scene& s = SceneOf(r, scene);
            py::list instances;
            for (size_t i = 0; i < s.instances.size(); ++i) {
              py::dict material = MaterialDict(s.InstanceMaterial(i));
              material["name"] = s.instances[i].name;
              instances.append(material);
            }
            py::list fixtures;
            for (const Scene::Fixture& f : s.fixtures) fixtures.append(MaterialDict(f.material));
            py::list lights;
            for (const LightSource& l : s.light_sources) lights.append(FieldsDict(l));
            return py::dict(
                "instances"_a = instances,
                "floor"_a = s.floor ? py::object(MaterialDict(s.floor_material)) : py::none(),
                "floor_half_size"_a = s.floor_half_size_mm, "fixtures"_a = fixtures,
                "lights"_a = lights, "environment"_a = FieldsDict(s.environment));
          },
          "scene"_a,
          R"(Scene `scene`'s look in the pbr mode before any randomisation, as the renderer
shades it: instances (one material per instance, in scene_gt_world.json's order, its `name` too),
floor (None without one), floor_half_size (mm), fixtures (one material each), lights and
environment. A material: the surface (base_color linear, metallic, roughness, specular,
anisotropic, clearcoat, clearcoat_roughness, distribution, and multiscatter as a bool), tangent,
base_from_part (its base colour already the instance's own), textured, and texture (type, scale
in mm, amount, roughness, bump, color, seed, file, projection) or None. Lights and the
environment: their recipe keys (lengths in mm, angles in radians; a rect's sides size_x, size_y;
type). For rebuilding a frame in another renderer (tools/cycles).)")
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
