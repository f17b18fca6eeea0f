#include "dataset/grasp_labels.h"

#include <algorithm>
#include <cmath>
#include <functional>

#include "cad/core/error.h"
#include "dataset/file_io.h"
#include "dataset/grasp.h"

namespace cadsynth {

namespace {

// The placed grasps of visible instances to write, per instance the best `max` by quality (ties
// in list order), in instance order.
std::vector<const PlacedGrasp*> Chosen(const Frame& frame, const std::vector<PlacedGrasp>& placed,
                                       int max,
                                       const std::function<double(const PlacedGrasp&)>& quality) {
  std::vector<const PlacedGrasp*> chosen;
  size_t begin = 0;
  while (begin < placed.size()) {
    size_t end = begin;
    while (end < placed.size() && placed[end].instance == placed[begin].instance) ++end;
    const int instance = placed[begin].instance;
    if (instance >= 0 && static_cast<size_t>(instance) < frame.instances.size() &&
        frame.instances[static_cast<size_t>(instance)].px_count_visib > 0) {
      std::vector<const PlacedGrasp*> group;
      for (size_t k = begin; k < end; ++k) group.push_back(&placed[k]);
      std::stable_sort(group.begin(), group.end(), [&](const PlacedGrasp* a, const PlacedGrasp* b) {
        return quality(*a) > quality(*b);
      });
      if (max > 0 && group.size() > static_cast<size_t>(max))
        group.resize(static_cast<size_t>(max));
      chosen.insert(chosen.end(), group.begin(), group.end());
    }
    begin = end;
  }
  return chosen;
}

int ObjId(const SceneGrasps& grasps, int instance) {
  return grasps.obj_id_of_instance.at(static_cast<size_t>(instance));
}

template <typename Grasp>
const Grasp& Lookup(const std::vector<std::vector<Grasp>>& lists, const SceneGrasps& grasps,
                    const PlacedGrasp& placed) {
  const int part = grasps.part_of_instance.at(static_cast<size_t>(placed.instance));
  return lists.at(static_cast<size_t>(part)).at(static_cast<size_t>(placed.grasp));
}

}  // namespace

bool GraspLabelOptions::Check(std::string* why) const {
  if (max_per_instance < 0 || max_per_instance > 1000000) {
    *why = "per_instance must be 0 (all) to 1,000,000";
  } else if (!(visibility_mm > 0 && visibility_mm <= 1000)) {
    *why = "visibility tolerance must lie in (0, 1000] mm";
  } else {
    return true;
  }
  return false;
}

bool PointSeen(const Frame& frame, int instance, const Eigen::Vector3d& p, double tolerance_mm) {
  Eigen::Vector2d uv;
  if (!frame.camera.intrinsics.Project(p, &uv)) return false;
  if (!(uv.x() > -2 && uv.y() > -2 && uv.x() < frame.width() + 2 && uv.y() < frame.height() + 2))
    return false;  // outside the image (and no int overflow below)
  const int u0 = static_cast<int>(std::floor(uv.x())), v0 = static_cast<int>(std::floor(uv.y()));
  const uint16_t id = static_cast<uint16_t>(instance + 1);
  for (int v = v0 - 1; v <= v0 + 1; ++v) {
    for (int u = u0 - 1; u <= u0 + 1; ++u) {
      if (u < 0 || v < 0 || u >= frame.width() || v >= frame.height()) continue;
      const size_t k =
          static_cast<size_t>(v) * static_cast<size_t>(frame.width()) + static_cast<size_t>(u);
      if (frame.instance[k] == id && std::abs(frame.depth[k] - p.z()) <= tolerance_mm) return true;
    }
  }
  return false;
}

std::vector<float> GraspNetRows(const Frame& frame, const SceneGrasps& grasps,
                                const GraspLabelOptions& options, std::vector<float>* labels) {
  std::vector<float> rows;
  labels->clear();
  if (grasps.jaw == nullptr) return rows;
  const auto quality = [&](const PlacedGrasp& p) { return Lookup(*grasps.jaw, grasps, p).quality; };
  for (const PlacedGrasp* placed :
       Chosen(frame, grasps.jaw_placed, options.max_per_instance, quality)) {
    const ParallelJawGrasp& g = Lookup(*grasps.jaw, grasps, *placed);
    const Eigen::Isometry3d& cam_from_model =
        frame.instances[static_cast<size_t>(placed->instance)].cam_from_model;
    const Eigen::Matrix3d r = (cam_from_model * g.model_from_gripper).linear();
    Eigen::Matrix3d graspnet;  // approach, closing, height
    graspnet.col(0) = r.col(2);
    graspnet.col(1) = r.col(0);
    graspnet.col(2) = r.col(2).cross(r.col(0));
    const Eigen::Vector3d c0 = cam_from_model * g.contacts[0];
    const Eigen::Vector3d c1 = cam_from_model * g.contacts[1];
    // graspnetAPI closes the jaws `depth` along the approach beyond the translation (its
    // evaluator's contact line is at translation + depth * approach): the translation is that far
    // back from the contacts' midpoint.
    const Eigen::Vector3d t = 0.5e-3 * (c0 + c1) - 1e-3 * g.depth_mm * graspnet.col(0);
    rows.push_back(static_cast<float>(g.quality));
    rows.push_back(static_cast<float>(1e-3 * g.opening_mm));
    rows.push_back(static_cast<float>(1e-3 * grasps.gripper.finger_width_mm));
    rows.push_back(static_cast<float>(1e-3 * g.depth_mm));
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) rows.push_back(static_cast<float>(graspnet(i, j)));
    }
    for (int i = 0; i < 3; ++i) rows.push_back(static_cast<float>(t[i]));
    const int obj_id = ObjId(grasps, placed->instance);
    rows.push_back(static_cast<float>(obj_id));
    labels->insert(labels->end(),
                   {static_cast<float>(placed->instance), static_cast<float>(obj_id),
                    placed->approach_blocked ? 1.0f : 0.0f,
                    PointSeen(frame, placed->instance, c0, options.visibility_mm) ? 1.0f : 0.0f,
                    PointSeen(frame, placed->instance, c1, options.visibility_mm) ? 1.0f : 0.0f,
                    static_cast<float>(placed->grasp)});
  }
  return rows;
}

std::vector<float> SuctionNetRows(const Frame& frame, const SceneGrasps& grasps,
                                  const GraspLabelOptions& options, std::vector<float>* labels) {
  std::vector<float> rows;
  labels->clear();
  if (grasps.suction == nullptr) return rows;
  const auto quality = [&](const PlacedGrasp& p) {
    return Lookup(*grasps.suction, grasps, p).quality();
  };
  for (const PlacedGrasp* placed :
       Chosen(frame, grasps.suction_placed, options.max_per_instance, quality)) {
    const SuctionGrasp& g = Lookup(*grasps.suction, grasps, *placed);
    const Eigen::Isometry3d& cam_from_model =
        frame.instances[static_cast<size_t>(placed->instance)].cam_from_model;
    const Eigen::Vector3d point = cam_from_model * g.point;
    const Eigen::Vector3d direction = -(cam_from_model.linear() * g.approach).normalized();
    rows.push_back(static_cast<float>(g.quality()));
    for (int i = 0; i < 3; ++i) rows.push_back(static_cast<float>(direction[i]));
    for (int i = 0; i < 3; ++i) rows.push_back(static_cast<float>(1e-3 * point[i]));
    rows.push_back(static_cast<float>(ObjId(grasps, placed->instance)));
    labels->insert(
        labels->end(),
        {static_cast<float>(placed->instance), static_cast<float>(ObjId(grasps, placed->instance)),
         placed->approach_blocked ? 1.0f : 0.0f,
         PointSeen(frame, placed->instance, point, options.visibility_mm) ? 1.0f : 0.0f,
         static_cast<float>(g.seal), static_cast<float>(g.wrench)});
  }
  return rows;
}

GraspLabelWriter::GraspLabelWriter(const std::filesystem::path& root, int scene_id,
                                   GraspLabelOptions options, SceneGrasps grasps)
    : graspnet_dir_(root / "graspnet" / Id6(scene_id)),
      suctionnet_dir_(root / "suctionnet" / Id6(scene_id)),
      options_(options),
      grasps_(std::move(grasps)) {
  std::string why;
  if (!options_.Check(&why)) throw Error("grasps: " + why);
  if (options_.graspnet) std::filesystem::create_directories(graspnet_dir_);
  if (options_.suctionnet) std::filesystem::create_directories(suctionnet_dir_);
}

void GraspLabelWriter::WriteFrame(int image_id, const Frame& frame, const BopFrameFiles&,
                                  FileLog* files) const {
  const std::string im = Id6(image_id);
  const auto write = [&](const std::filesystem::path& path, const std::string& bytes) {
    if (files != nullptr) {
      files->Write(path, bytes);
    } else {
      WriteFileAtomic(path, bytes);
    }
  };
  std::vector<float> labels;
  if (options_.graspnet) {
    const std::vector<float> rows = GraspNetRows(frame, grasps_, options_, &labels);
    write(graspnet_dir_ / (im + ".npy"), EncodeNpy(rows.data(), rows.size() / 17, 17));
    write(graspnet_dir_ / (im + "_labels.npy"), EncodeNpy(labels.data(), labels.size() / 6, 6));
  }
  if (options_.suctionnet) {
    const std::vector<float> rows = SuctionNetRows(frame, grasps_, options_, &labels);
    write(suctionnet_dir_ / (im + ".npy"), EncodeNpy(rows.data(), rows.size() / 8, 8));
    write(suctionnet_dir_ / (im + "_labels.npy"), EncodeNpy(labels.data(), labels.size() / 6, 6));
  }
}

}  // namespace cadsynth
