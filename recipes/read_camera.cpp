// The camera (a preset, K, the sensor), a rig of named cameras and the sweep of views.
#include "recipes/sections.h"

#include <algorithm>

#include <Eigen/SVD>

namespace cadsynth::recipe_detail {

// A camera's keys (`camera:`, or an entry of `cameras:` with its `other` keys read elsewhere).
void ReadCamera(const Reader& r, const YAML::Node& node, const std::string& key, Intrinsics* kp,
                SensorOptions* sensor, const Key& schema) {
  r.ExpectKeys(node, key, schema);
  Intrinsics& k = *kp;
  if (node["preset"]) {
    const std::string preset = r.Scalar(node["preset"], key + ".preset");
    const CameraPreset* found = FindCameraPreset(preset);
    if (found == nullptr) {
      std::string known;
      for (const CameraPreset& p : CameraPresets())
        known += (known.empty() ? "" : ", ") + std::string(p.name);
      r.Fail(node["preset"], key + ".preset",
             "unknown preset '" + preset + "' (known: " + known + ")");
    }
    k = found->intrinsics;
    if (found->gray) sensor->image = SensorOptions::Image::kGray;
  }
  ReadDescribed(r, node, key, &k);
  // A field of view in place of fx, fy, cx and cy: from the width and the height.
  if (node["hfov"]) {
    const double hfov = r.Angle(node["hfov"], key + ".hfov");
    if (!(hfov > 0 && hfov < M_PI))
      r.Fail(node["hfov"], key + ".hfov", "must lie between 0 and 180 degrees");
    if (node["fx"] || node["fy"] || node["cx"] || node["cy"])
      r.Fail(node["hfov"], key + ".hfov", "give hfov or fx/fy/cx/cy, not both");
    k = Intrinsics::FromFov(k.width, k.height, hfov);
  }
  if (const YAML::Node distortion = node["distortion"]) {
    ReadFields(r, distortion, key + ".distortion", &k.distortion, SchemaAt("camera.distortion"));
    r.Check(k, distortion, key + ".distortion");
  }
  r.Check(k, node, key);
  if (const YAML::Node lens = node["lens"]) {
    ReadFields(r, lens, key + ".lens", &sensor->lens, SchemaAt("camera.lens"));
    if (!lens["focal_length"])
      r.Fail(lens, key + ".lens", "give the lens's 'focal_length' (with f_number: the aperture)");
    r.Check(sensor->lens, lens, key + ".lens");
  }
  // motion: the camera's velocities in its own frame while the shutter is open.
  if (const YAML::Node motion = node["motion"]) {
    const std::string at = key + ".motion";
    r.ExpectKeys(motion, at, SchemaAt("camera.motion"));
    if (!motion["exposure_ms"])
      r.Fail(motion, at, "give 'exposure_ms', how long the shutter is open");
    ReadDescribed(r, motion, at, &sensor->motion);
    r.Check(sensor->motion, motion, at);
  }
  ReadDescribed(r, node, key, sensor);  // the image
  if (const YAML::Node imager = node["imager"]) {
    ReadFields(r, imager, key + ".imager", &sensor->imager, SchemaAt("camera.imager"));
    r.Check(sensor->imager, imager, key + ".imager");
  }
  // depth: a model's name, or {model: NAME, KEY: VALUE...} overriding the model's defaults.
  if (const YAML::Node depth = node["depth"]) {
    const YAML::Node model = depth.IsMap() ? depth["model"] : depth;
    if (!model) r.Fail(depth, key + ".depth", "give the sensor's 'model'");
    const std::string model_key = depth.IsMap() ? key + ".depth.model" : key + ".depth";
    DepthModel m;
    DepthModel::Fields(m, [&](auto& value, const Field& field) {
      if constexpr (std::is_enum_v<std::decay_t<decltype(value)>>) {
        if (field.key == "model") ReadField(r, model, model_key, field, &value);
      }
    });
    m = DepthModel::Defaults(m.kind);
    if (depth.IsMap()) ReadFields(r, depth, key + ".depth", &m, SchemaAt("camera.depth"));
    r.Check(m, depth, key + ".depth");
    sensor->depth = m;
  }
}

void ReadSweep(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  r.ExpectKeys(node, "sweep", SchemaAt("sweep"));
  // Each axis a series (the recipe's own syntax); the target, the sampler and the jitter described.
  const auto angle = [&](const YAML::Node& n, const std::string& k) { return r.Angle(n, k); };
  const auto length = [&](const YAML::Node& n, const std::string& k) { return r.Length(n, k); };
  SweepOptions& s = spec->sweep;
  if (node["yaw"]) s.yaw_rad = r.Series(node["yaw"], "sweep.yaw", angle);
  if (node["pitch"]) s.pitch_rad = r.Series(node["pitch"], "sweep.pitch", angle);
  if (node["radius"]) {
    // (A camera closer than 10 mm is no sweep: 0.8 meant metres.)
    r.CheckMetresMeant(node["radius"], "sweep.radius", 10.0);
    s.radius_mm = r.Series(node["radius"], "sweep.radius", length);
  }
  ReadDescribed(r, node, "sweep", &s);
  r.Check(s, node, "sweep");
  ViewSampler& v = spec->sampler;
  ReadDescribed(r, node, "sweep", &v);
  // (A negative seed wraps.)
  if (node["seed"]) v.seed = static_cast<uint64_t>(r.Integer(node["seed"], "sweep.seed"));
  ReadDescribed(r, node, "sweep", spec);  // min_visible_pixels (RunSpec's own)
  // Fibonacci and random views fill the band between the lowest and highest pitch; random radii the
  // range between the smallest and largest radius.
  v.min_pitch_rad = *std::min_element(s.pitch_rad.begin(), s.pitch_rad.end());
  v.max_pitch_rad = *std::max_element(s.pitch_rad.begin(), s.pitch_rad.end());
  v.min_radius_mm = *std::min_element(s.radius_mm.begin(), s.radius_mm.end());
  v.max_radius_mm = *std::max_element(s.radius_mm.begin(), s.radius_mm.end());
  r.Check(v, node, "sweep");
}

// `cameras:`, a rig: a list of cameras with names, the first one the rig's frame (the sweep
// places it) and the others fixed to it by `position` and `look_at` or `rotation`.
void ReadCameras(const Reader& r, const YAML::Node& node, RunSpec* spec) {
  constexpr size_t kMaxSensors = 16;
  if (!node.IsSequence() || node.size() == 0)
    r.Fail(node, "cameras", "expected a list of cameras (a rig), each with a 'name'");
  if (node.size() > kMaxSensors)
    r.Fail(node, "cameras", "at most " + std::to_string(kMaxSensors) + " cameras in a rig");
  spec->rig.clear();
  for (size_t i = 0; i < node.size(); ++i) {
    const YAML::Node entry = node[i];
    const std::string key = "cameras[" + std::to_string(i) + "]";
    RigSensor sensor;
    sensor.where = r.Where(entry);
    ReadCamera(r, entry, key, &sensor.intrinsics, &sensor.sensor, SchemaAt("cameras[]"));
    if (i > 0 && entry["motion"]) {
      r.Fail(entry["motion"], key + ".motion",
             "the rig moves as one: give its motion on the first camera (the rig's frame)");
    }
    if (!entry["name"]) r.Fail(entry, key, "a rig's camera needs a 'name' (e.g. xyz, realsense)");
    sensor.name = r.Scalar(entry["name"], key + ".name");
    // BOP appends the name to folder names (rgb_NAME/): lower-case letters and digits only.
    const bool plain = !sensor.name.empty() && sensor.name.size() <= 32 &&
                       std::all_of(sensor.name.begin(), sensor.name.end(), [](char c) {
                         return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
                       });
    if (!plain) {
      r.Fail(
          entry["name"], key + ".name",
          "'" + sensor.name + "': use 1-32 lower-case letters and digits (BOP writes rgb_NAME/)");
    }
    // scene_gt_NAME.json must not read as BOP's scene_gt_info.json, scene_gt_coco.json or our
    // scene_gt_world.json.
    for (const char* taken : {"info", "coco", "world"}) {
      if (sensor.name.rfind(taken, 0) == 0) {
        r.Fail(entry["name"], key + ".name",
               "'" + sensor.name +
                   "': names starting with info, coco or world would make scene_gt_NAME.json "
                   "look like BOP's scene_gt_info.json and its kin");
      }
    }
    for (const RigSensor& earlier : spec->rig) {
      if (earlier.name == sensor.name)
        r.Fail(entry["name"], key + ".name", "'" + sensor.name + "' names two cameras");
    }
    if (i == 0) {
      for (const char* pose : {"position", "look_at", "rotation"}) {
        if (entry[pose]) {
          r.Fail(entry[pose], key + "." + pose,
                 "the first camera is the rig's frame (the sweep places it): give the others' "
                 "poses relative to it");
        }
      }
    }
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    if (entry["position"]) position = Triple(r, entry["position"], key + ".position", true);
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    if (entry["look_at"] && entry["rotation"])
      r.Fail(entry["rotation"], key + ".rotation", "give 'look_at' or 'rotation', not both");
    if (entry["look_at"]) {
      // z towards the point; x along the rig's y (down) x z, so the image does not roll.
      const Eigen::Vector3d at = Triple(r, entry["look_at"], key + ".look_at", true);
      const Eigen::Vector3d z = (at - position).normalized();
      const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);
      if (!((at - position).norm() > 1e-9) || x.norm() < 1e-6) {
        r.Fail(entry["look_at"], key + ".look_at",
               "must lie away from the camera and not straight above or below it (the rig's y)");
      }
      rotation.col(0) = x.normalized();
      rotation.col(2) = z;
      rotation.col(1) = z.cross(rotation.col(0));
    } else if (const YAML::Node rot = entry["rotation"]) {
      if (!rot.IsSequence() || rot.size() != 9) {
        r.Fail(rot, key + ".rotation",
               "expected the 9 numbers of rig_R_cam, row-major (the camera's axes as columns)");
      }
      for (int k = 0; k < 9; ++k) rotation(k / 3, k % 3) = r.Number(rot[k], key + ".rotation");
      if ((rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).norm() > 1e-4 ||
          rotation.determinant() < 0) {
        r.Fail(rot, key + ".rotation", "is not a rotation (orthonormal, determinant 1, to 1e-4)");
      }
      // Calibration files print 6-8 digits: the nearest exact rotation.
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(rotation,
                                                  Eigen::ComputeFullU | Eigen::ComputeFullV);
      rotation = svd.matrixU() * svd.matrixV().transpose();
    }
    sensor.rig_from_cam.linear() = rotation;
    sensor.rig_from_cam.translation() = position;
    // The rig's motion, as each camera on it sees it.
    if (i > 0) sensor.sensor.motion = spec->rig[0].sensor.motion.Seen(sensor.rig_from_cam);
    spec->rig.push_back(std::move(sensor));
  }
  spec->intrinsics = spec->rig[0].intrinsics;
  spec->sensor = spec->rig[0].sensor;
}

}  // namespace cadsynth::recipe_detail
