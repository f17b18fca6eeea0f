// A rendered frame as Python gets it: a dict of numpy arrays, exactly what the writer encodes. The
// keys, their dtypes, shapes and units are documented in cadsynth/_cadsynth.pyi (class Frame);
// the order they are added in is the order Python sees.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <vector>

#include "cad/core/error.h"
#include "dataset/bop.h"
#include "dataset/grasp_labels.h"
#include "recipes/recipe.h"
#include "tools/python/bindings.h"

namespace cadsynth::python {
namespace {

py::array_t<double> Matrix4(const Eigen::Isometry3d& pose) {
  py::array_t<double> out({4, 4});
  auto m = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = pose.matrix()(r, c);
  }
  return out;
}

// The image's ids and its camera (scene_camera.json).
void AddCamera(py::dict& d, const Frame& frame, const FrameSource& source, const RigSensor& rig,
               size_t scene, size_t view, const BopOptions& bop) {
  d["scene_id"] = scene;
  d["im_id"] = view;
  if (!rig.name.empty()) d["sensor"] = rig.name;
  d["width"] = frame.width();
  d["height"] = frame.height();
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
  if (source.spec().min_visible_pixels <= 0) {
    d["split"] = bop.IsTest(static_cast<int>(view), static_cast<int>(source.views().size()))
                     ? "test"
                     : "train";
  }
}

// Per instance, BOP's ground truth (scene_gt.json, scene_gt_info.json).
void AddInstances(py::dict& d, const Frame& frame, const std::vector<int>& obj_ids,
                  const std::vector<GtInfo>& infos) {
  const size_t n = frame.instances.size();
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
}

// The full silhouette and the visible part (BOP's mask/ and mask_visib/), as bool.
void AddMasks(py::dict& d, const Frame& frame, const BopOptions& bop,
              const std::vector<GtInfo>& infos) {
  const py::ssize_t w = frame.width(), h = frame.height();
  const size_t pixels = static_cast<size_t>(w) * static_cast<size_t>(h);
  const size_t n = frame.instances.size();
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

// As the GraspNet / SuctionNet files hold them. Read before the images are moved out of the
// frame: visibility looks at depth and ids.
void AddGrasps(py::dict& d, const Frame& frame, const SceneGrasps& grasps,
               const GraspLabelOptions& options) {
  if (options.graspnet) {
    std::vector<float> labels;
    std::vector<float> rows = GraspNetRows(frame, grasps, options, &labels);
    const auto m = static_cast<py::ssize_t>(rows.size() / 17);
    d["graspnet"] = Own(std::move(rows), {m, 17});
    d["graspnet_labels"] = Own(std::move(labels), {m, 6});
  }
  if (options.suctionnet) {
    std::vector<float> labels;
    std::vector<float> rows = SuctionNetRows(frame, grasps, options, &labels);
    const auto m = static_cast<py::ssize_t>(rows.size() / 8);
    d["suctionnet"] = Own(std::move(rows), {m, 8});
    d["suctionnet_labels"] = Own(std::move(labels), {m, 6});
  }
}

// The images, moved out of the frame into the arrays.
void AddImages(py::dict& d, Frame& frame, const BopOptions& bop) {
  const py::ssize_t w = frame.width(), h = frame.height();
  const size_t pixels = static_cast<size_t>(w) * static_cast<size_t>(h);
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
  if (!frame.denoiser_inputs.radiance.empty()) {
    Frame::DenoiserInputs& in = frame.denoiser_inputs;
    d["denoiser_radiance"] = Own(std::move(in.radiance), {h, w, 3});
    d["denoiser_albedo"] = Own(std::move(in.albedo), {h, w, 3});
    d["denoiser_normal"] = Own(std::move(in.normal), {h, w, 3});
    d["denoiser_variance"] = Own(std::move(in.variance), {h, w});
  }
  if (!frame.samples.empty()) {
    // int32, which PyTorch converts (it has no uint32 tensors); at most 65,536 paths.
    std::vector<int32_t> samples(frame.samples.begin(), frame.samples.end());
    d["samples"] = Own(std::move(samples), {h, w});
  }
  if (!frame.randomization.empty()) d["randomization"] = frame.randomization;
}

py::dict SensorDict(Frame&& frame, const FrameSource& source, size_t scene, size_t view,
                    size_t sensor, const FrameOptions& options) {
  const RunSpec& spec = source.spec();
  const RigSensor& rig = source.sensors()[sensor];
  BopOptions bop = spec.bop;
  bop.gray_bits = spec.rig.empty() ? spec.bop.gray_bits : GrayBits(rig.sensor.image);
  py::dict d;
  AddCamera(d, frame, source, rig, scene, view, bop);
  const std::vector<GtInfo> infos = ComputeGtInfos(frame, bop);
  AddInstances(d, frame, source.prepared().obj_ids[scene], infos);
  if (options.masks) AddMasks(d, frame, bop, infos);
  // Grasps (grasps:) for the first sensor only, like the other derived formats.
  if (sensor == 0 && spec.grasps.enabled) {
    AddGrasps(d, frame, source.PlacedGrasps(scene), spec.grasps.labels);
  }
  AddImages(d, frame, bop);
  return d;
}

}  // namespace

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

}  // namespace cadsynth::python
