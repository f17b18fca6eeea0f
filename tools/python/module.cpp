// The Python module `cadsynth` (its compiled part, cadsynth._cadsynth): recipes, prepared runs and
// their frames as dicts of numpy arrays, over the same pipeline library the command line uses
// (tools/pipeline/frames.h). The pure-Python part (tools/python/cadsynth/) adds the torch dataset.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <tbb/global_control.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "dataset/bop.h"
#include "dataset/grasp_labels.h"
#include "recipes/recipe.h"
#include "tools/pipeline/eval.h"
#include "tools/pipeline/frames.h"
#include "tools/pipeline/generate.h"
#include "tools/pipeline/shards.h"

namespace py = pybind11;
using namespace pybind11::literals;

namespace cadsynth {
namespace {

// A numpy array that owns `values` (moved into it, not copied).
template <class T>
py::array_t<T> Own(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule free(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, owned->data(), free);
}

py::array_t<double> Matrix4(const Eigen::Isometry3d& pose) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = pose.matrix()(r, c);
  }
  return out;
}

// The part cache the command line uses by default, or another folder, or none.
std::optional<std::filesystem::path> CacheFolder(const py::object& cache) {
  if (cache.is_none()) return std::nullopt;
  if (py::isinstance<py::bool_>(cache)) {
    if (!cache.cast<bool>()) return std::nullopt;
    return PartCache::DefaultDirectory();
  }
  return cache.cast<std::filesystem::path>();
}

std::optional<ShardSpec> ShardOf(const py::object& shard) {
  if (shard.is_none()) return std::nullopt;
  if (py::isinstance<py::str>(shard)) return ParseShard(shard.cast<std::string>());
  const auto pair = shard.cast<std::pair<int, int>>();
  return ParseShard(std::to_string(pair.first) + "/" + std::to_string(pair.second));
}

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

struct PyRun;

// What one frame (one sensor's) becomes in Python: a dict of numpy arrays.
struct FrameOptions {
  bool masks = true;  // N x H x W masks (the instance image is always there)
};

py::dict SensorDict(Frame&& frame, const FrameSource& source, size_t scene, size_t view,
                    size_t sensor, const FrameOptions& options) {
  const RunSpec& spec = source.spec();
  const RigSensor& rig = source.sensors()[sensor];
  BopOptions bop = spec.bop;
  bop.gray_bits = spec.rig.empty() ? spec.bop.gray_bits : GrayBits(rig.sensor.image);
  const py::ssize_t w = frame.width(), h = frame.height();
  const size_t pixels = static_cast<size_t>(w) * static_cast<size_t>(h);
  const size_t n = frame.instances.size();
  py::dict d;
  d["scene_id"] = scene;
  d["im_id"] = view;
  if (!rig.name.empty()) d["sensor"] = rig.name;
  d["width"] = w;
  d["height"] = h;
  {
    py::array_t<double> k({3, 3});
    auto m = k.mutable_unchecked<2>();
    const Eigen::Matrix3d kmat = frame.camera.intrinsics.K();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) m(r, c) = kmat(r, c);
    }
    d["K"] = k;
  }
  d["cam_from_world"] = Matrix4(frame.camera.world_from_cam.inverse());
  d["depth_scale"] = bop.depth_scale;
  // The image's split as the writer assigns it (by its place among the scene's written images:
  // known while streaming only when no view is skipped).
  if (spec.min_visible_pixels <= 0) {
    d["split"] = bop.IsTest(static_cast<int>(view), static_cast<int>(source.views().size()))
                     ? "test"
                     : "train";
  }

  // Per instance, BOP's ground truth (scene_gt.json, scene_gt_info.json).
  const std::vector<GtInfo> infos = ComputeGtInfos(frame, bop);
  const std::vector<int>& obj_ids = source.prepared().obj_ids[scene];
  py::array_t<int32_t> obj_id(static_cast<py::ssize_t>(n));
  py::array_t<double> cam_from_model({static_cast<py::ssize_t>(n), py::ssize_t{4}, py::ssize_t{4}});
  py::array_t<int32_t> bbox_obj({static_cast<py::ssize_t>(n), py::ssize_t{4}});
  py::array_t<int32_t> bbox_visib({static_cast<py::ssize_t>(n), py::ssize_t{4}});
  py::array_t<int32_t> px_all(static_cast<py::ssize_t>(n)), px_valid(static_cast<py::ssize_t>(n)),
      px_visib(static_cast<py::ssize_t>(n));
  py::array_t<double> visib_fract(static_cast<py::ssize_t>(n));
  {
    auto id = obj_id.mutable_unchecked<1>();
    auto pose = cam_from_model.mutable_unchecked<3>();
    auto bo = bbox_obj.mutable_unchecked<2>();
    auto bv = bbox_visib.mutable_unchecked<2>();
    auto pa = px_all.mutable_unchecked<1>();
    auto pd = px_valid.mutable_unchecked<1>();
    auto pv = px_visib.mutable_unchecked<1>();
    auto vf = visib_fract.mutable_unchecked<1>();
    for (size_t i = 0; i < n; ++i) {
      const auto k = static_cast<py::ssize_t>(i);
      id(k) = obj_ids[i];
      const Eigen::Matrix4d m = frame.instances[i].cam_from_model.matrix();
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) pose(k, r, c) = m(r, c);
      }
      for (int c = 0; c < 4; ++c) {
        bo(k, c) = infos[i].bbox_obj[c];
        bv(k, c) = infos[i].bbox_visib[c];
      }
      pa(k) = infos[i].px_count_all;
      pd(k) = infos[i].px_count_valid;
      pv(k) = infos[i].px_count_visib;
      vf(k) = infos[i].visib_fract;
    }
  }
  d["obj_id"] = obj_id;
  d["cam_from_model"] = cam_from_model;
  d["bbox_obj"] = bbox_obj;
  d["bbox_visib"] = bbox_visib;
  d["px_count_all"] = px_all;
  d["px_count_valid"] = px_valid;
  d["px_count_visib"] = px_visib;
  d["visib_fract"] = visib_fract;

  // Masks: the full silhouette and the visible part (BOP's mask/ and mask_visib/), as bool.
  if (options.masks) {
    const std::vector<py::ssize_t> shape = {static_cast<py::ssize_t>(n), h, w};
    py::array_t<bool> full(shape), visib(shape);
    auto* f = full.mutable_data();
    auto* v = visib.mutable_data();
    std::memset(f, 0, n * pixels);
    std::memset(v, 0, n * pixels);
    const VisibleMasks visible(frame, bop);
    for (size_t i = 0; i < n; ++i) {
      const Frame::InstanceTruth& truth = frame.instances[i];
      const auto [r0, r1, r2, r3] = truth.Roi(static_cast<int>(w), static_cast<int>(h));
      bool* out = f + i * pixels;
      for (int y = r1; y < r3 && !truth.amodal_mask.empty(); ++y) {
        const uint8_t* in = &truth.amodal_mask[static_cast<size_t>(y - r1) * (r2 - r0)];
        for (int x = r0; x < r2; ++x)
          out[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)] =
              in[x - r0] != 0;
      }
      const int* b = infos[i].bbox_visib;
      if (infos[i].px_count_visib == 0) continue;
      bool* vis = v + i * pixels;
      for (int y = b[1]; y <= b[1] + b[3]; ++y) {
        for (int x = b[0]; x <= b[0] + b[2]; ++x)
          vis[static_cast<size_t>(y) * static_cast<size_t>(w) + static_cast<size_t>(x)] =
              visible(i, x, y);
      }
    }
    d["mask"] = full;
    d["mask_visib"] = visib;
  }

  // Grasps (grasps:), for the first sensor, as the GraspNet / SuctionNet files hold them (read
  // before the images are moved out of the frame: visibility looks at depth and ids).
  if (sensor == 0 && spec.grasps.enabled) {
    const SceneGrasps& grasps = source.PlacedGrasps(scene);
    if (spec.grasps.labels.graspnet) {
      std::vector<float> labels;
      std::vector<float> rows = GraspNetRows(frame, grasps, spec.grasps.labels, &labels);
      const auto m = static_cast<py::ssize_t>(rows.size() / 17);
      d["graspnet"] = Own(std::move(rows), {m, 17});
      d["graspnet_labels"] = Own(std::move(labels), {m, 6});
    }
    if (spec.grasps.labels.suctionnet) {
      std::vector<float> labels;
      std::vector<float> rows = SuctionNetRows(frame, grasps, spec.grasps.labels, &labels);
      const auto m = static_cast<py::ssize_t>(rows.size() / 8);
      d["suctionnet"] = Own(std::move(rows), {m, 8});
      d["suctionnet_labels"] = Own(std::move(labels), {m, 6});
    }
  }
  // The camera's image: colour, or grey as the file holds it (8 or 16 bits).
  if (bop.gray_bits > 0) {
    if (frame.gray.size() != pixels) throw Error("a grey camera's frame has no grey image");
    if (bop.gray_bits == 16) {
      std::vector<uint16_t> gray(pixels);
      for (size_t p = 0; p < pixels; ++p) gray[p] = EncodeGray(frame.gray[p], 16);
      d["gray"] = Own(std::move(gray), {h, w});
    } else {
      std::vector<uint8_t> gray(pixels);
      for (size_t p = 0; p < pixels; ++p)
        gray[p] = static_cast<uint8_t>(EncodeGray(frame.gray[p], 8));
      d["gray"] = Own(std::move(gray), {h, w});
    }
  } else {
    d["rgb"] = Own(std::move(frame.rgb), {h, w, 3});
  }
  // depth: what the sensor returns (depth/); depth_gt: the exact depth, with a depth model.
  if (frame.sensor_depth.empty()) {
    d["depth"] = Own(std::move(frame.depth), {h, w});
  } else {
    d["depth"] = Own(std::move(frame.sensor_depth), {h, w});
    d["depth_gt"] = Own(std::move(frame.depth), {h, w});
  }
  d["instance"] = Own(std::move(frame.instance), {h, w});
  if (!frame.infrared.empty()) d["ir"] = Own(std::move(frame.infrared), {h, w});
  if (!frame.normals.empty()) {
    std::vector<float> normals(3 * pixels);
    for (size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < 3; ++c) normals[3 * p + static_cast<size_t>(c)] = frame.normals[p][c];
    }
    d["normals"] = Own(std::move(normals), {h, w, 3});
  }
  if (!frame.radiance.empty()) d["radiance"] = Own(std::move(frame.radiance), {h, w, 3});
  if (!frame.randomization.empty()) d["randomization"] = frame.randomization;

  return d;
}

// A rendered view as Python sees it: the first sensor's dict, with every sensor's dict under
// "sensors" for a rig of several.
py::dict ViewDict(RenderedView&& view, const FrameSource& source, const FrameOptions& options) {
  const size_t sensors = view.frames.size();
  std::vector<py::dict> dicts;
  for (size_t k = 0; k < sensors; ++k) {
    dicts.push_back(
        SensorDict(std::move(view.frames[k]), source, view.scene, view.view, k, options));
  }
  if (sensors == 1) return dicts[0];
  py::dict out = dicts[0].attr("copy")();  // not dicts[0] itself: no cycle through "sensors"
  out["sensors"] = dicts;
  return out;
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

// A prepared run in Python.
struct PyRun {
  std::shared_ptr<const FrameSource> source;
};

py::dict SummaryDict(const GenerateSummary& s) {
  return py::dict("frames"_a = s.frames, "resumed"_a = s.resumed,
                  "skipped_empty"_a = s.skipped_empty, "skipped_sparse"_a = s.skipped_sparse,
                  "scenes"_a = s.scenes, "objects"_a = s.objects, "instances"_a = s.instances,
                  "seconds"_a = s.seconds);
}

GenerateOptions WriteOptions(const std::filesystem::path& output, bool overwrite,
                             const py::object& shard) {
  GenerateOptions options;
  options.output = output;
  options.overwrite = overwrite;
  options.shard = ShardOf(shard);
  return options;
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
}  // namespace cadsynth

PYBIND11_MODULE(_cadsynth, m) {
  using namespace cadsynth;
  m.doc() = "cadsynth: CAD to labelled RGB-D frames (the compiled part; import cadsynth)";
  py::register_exception<Error>(m, "Error", PyExc_RuntimeError);

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
          [](const PyRecipe& r, const py::object& cache, int threads, bool verbose) {
            FrameSourceOptions options;
            options.cache = CacheFolder(cache);
            if (verbose) {
              options.info = [](const std::string& line) {
                py::gil_scoped_acquire acquire;
                py::print(line, "file"_a = py::module_::import("sys").attr("stderr"));
              };
            }
            PyRun run;
            run.source = Released(
                threads, [&] { return std::make_shared<const FrameSource>(r.spec, options); });
            return run;
          },
          "cache"_a = true, "threads"_a = 0, "verbose"_a = false,
          R"(Reads and builds the parts, arranges (or drops) every scene and plans the views.

cache: True (the command line's part cache), False/None, or a folder.
threads: at most this many threads (0: all cores).)")
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
of numpy arrays: rgb (or gray), depth (mm), instance, mask and mask_visib (N x H x W), obj_id,
cam_from_model (N x 4 x 4), bbox_obj, bbox_visib, visib_fract, K, ... (docs/python.md).

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

  m.def(
      "encode_png",
      [](const py::array& image) {
        const py::buffer_info info = image.request();
        if (info.ndim != 2 && !(info.ndim == 3 && (info.shape[2] == 1 || info.shape[2] == 3)))
          throw Error("encode_png: an image is H x W or H x W x 3");
        const bool deep = info.itemsize == 2;
        if (!(info.itemsize == 1 || deep) || !(py::isinstance<py::array_t<uint8_t>>(image) ||
                                               py::isinstance<py::array_t<uint16_t>>(image)))
          throw Error("encode_png: pixels are uint8 or uint16");
        const py::array contiguous =
            py::array::ensure(image, py::array::c_style | py::array::forcecast);
        const py::buffer_info c = contiguous.request();
        const int channels = info.ndim == 3 ? static_cast<int>(info.shape[2]) : 1;
        const std::string png =
            EncodeImagePng(c.ptr, static_cast<int>(info.shape[1]), static_cast<int>(info.shape[0]),
                           channels, deep ? 16 : 8);
        return py::bytes(png);
      },
      "image"_a, "PNG bytes of an H x W (x 3, RGB) uint8 or uint16 image, as the writer encodes.");
  m.def(
      "encode_depth",
      [](const py::array_t<float, py::array::c_style | py::array::forcecast>& depth,
         double depth_scale) {
        const auto in = depth.unchecked();
        std::vector<py::ssize_t> shape(depth.shape(), depth.shape() + depth.ndim());
        py::array_t<uint16_t> out(shape);
        const float* src = depth.data();
        uint16_t* dst = out.mutable_data();
        for (py::ssize_t i = 0; i < in.size(); ++i) dst[i] = EncodeDepth(src[i], depth_scale);
        return out;
      },
      "depth_mm"_a, "depth_scale"_a = 1.0,
      "Depth in mm as BOP's uint16 image holds it (value * depth_scale = mm; 0: none).");
  m.def(
      "read_image",
      [](const std::filesystem::path& path) -> py::array {
        DecodedImage image = ReadImageFile(path);
        std::vector<py::ssize_t> shape = {image.height, image.width};
        if (image.channels == 3) shape.push_back(3);
        if (image.bits == 8) return Own(std::move(image.bytes), shape);
        std::vector<uint16_t> values(image.bytes.size() / 2);
        std::memcpy(values.data(), image.bytes.data(), image.bytes.size());
        return Own(std::move(values), shape);
      },
      "path"_a, "Reads a PNG or JPEG image (RGB order for colour; uint8 or uint16).");
  m.def(
      "evaluate",
      [](const std::filesystem::path& dataset, const std::filesystem::path& results,
         const std::string& sensor) {
        EvalReport report;
        {
          py::gil_scoped_release release;
          report = Evaluate(dataset, results, sensor);
        }
        const py::object json = py::module_::import("json").attr("loads")(EvalJson(report));
        return py::make_tuple(EvalTable(report), json);
      },
      "dataset"_a, "results"_a, "sensor"_a = "",
      "Scores a BOP results CSV against a dataset, as `cadsynth eval`: (the table it prints, its "
      "--json report as a dict).");
  m.def(
      "default_cache", [] { return PartCache::DefaultDirectory(); },
      "The part cache folder the command line uses by default.");
  m.attr("__version__") = CADSYNTH_VERSION;
}
