// Camera rigs: one BopSceneWriter per sensor, sharing image ids, and BOP 2025's multi-view test
// targets over the sensors.
#include <algorithm>
#include <iterator>
#include <memory>

#include "cad/core/error.h"
#include "dataset/bop.h"
#include "dataset/bop_internal.h"

namespace cadsynth {

using bop_internal::Json;

RigSceneWriter::RigSceneWriter(const std::filesystem::path& root, int scene_id,
                               const BopOptions& options,
                               const std::vector<int>& obj_id_of_instance,
                               const std::vector<BopSensor>& sensors) {
  if (sensors.empty()) throw Error("bop: a rig needs at least one sensor");
  for (const BopSensor& sensor : sensors) {
    if (sensors.size() > 1 && sensor.name.empty()) throw Error("bop: a rig's sensors need names");
    sensors_.push_back(
        std::make_unique<BopSceneWriter>(root, scene_id, options, obj_id_of_instance, sensor));
  }
}

void RigSceneWriter::WriteFrame(int image_id, const std::vector<const Frame*>& frames,
                                const std::vector<const FrameWriter*>& formats) {
  if (frames.size() != sensors_.size()) {
    throw Error("bop: " + std::to_string(frames.size()) + " frames for a rig of " +
                std::to_string(sensors_.size()) + " sensors");
  }
  for (size_t k = 0; k < sensors_.size(); ++k) {
    sensors_[k]->WriteFrame(image_id, *frames[k],
                            k == 0 ? formats : std::vector<const FrameWriter*>{});
  }
}

bool RigSceneWriter::HasFrame(int image_id) const {
  for (const auto& sensor : sensors_) {
    if (!sensor->HasFrame(image_id)) return false;
  }
  return true;
}

std::vector<int> RigSceneWriter::WrittenFrames() const {
  std::vector<int> ids = sensors_[0]->WrittenFrames();
  for (size_t k = 1; k < sensors_.size(); ++k) {
    const std::vector<int> other = sensors_[k]->WrittenFrames();
    std::vector<int> both;
    std::set_intersection(ids.begin(), ids.end(), other.begin(), other.end(),
                          std::back_inserter(both));
    ids = std::move(both);
  }
  return ids;
}

std::string RigSceneWriter::CheckFrame(int image_id) const {
  for (const auto& sensor : sensors_) {
    std::string problem = sensor->CheckFrame(image_id);
    if (!problem.empty()) return problem;
  }
  return {};
}

void RigSceneWriter::ForgetFrame(int image_id) {
  for (const auto& sensor : sensors_) sensor->ForgetFrame(image_id);
}

std::vector<SceneSplit> RigSceneWriter::Finish() {
  // A frame one sensor wrote and another did not (a run stopped between them) is not complete:
  // it is rendered again before any finish, so here every sensor holds the same frames.
  const std::vector<int> complete = WrittenFrames();
  std::vector<SceneSplit> splits;
  for (const auto& sensor : sensors_) {
    if (sensor->WrittenFrames() != complete) {
      throw Error(sensor->scene_dir().string() + ": sensor '" + sensor->sensor().name +
                  "' holds frames the rig's other sensors lack");
    }
    splits.push_back(sensor->Finish());
  }
  return splits;
}

void RigSceneWriter::RemoveFragments() {
  for (const auto& sensor : sensors_) sensor->RemoveFragments();
}

void RigSceneWriter::WriteSequence(const SequenceStep& step) { sensors_[0]->WriteSequence(step); }

void RigSceneWriter::WriteRest(const SceneRest& rest) { sensors_[0]->WriteRest(rest); }

void RigSceneWriter::WriteWorldPoses(const std::vector<Instance>& instances) {
  sensors_[0]->WriteWorldPoses(instances);
}

void RigSceneWriter::SetCocoCategories(
    const std::vector<BopSceneWriter::CocoCategory>& categories) {
  for (const auto& sensor : sensors_) sensor->SetCocoCategories(categories);
}

void WriteMultiviewTargets(const std::filesystem::path& root, const std::vector<SceneSplit>& scenes,
                           const std::vector<BopSensor>& sensors) {
  Json targets = Json::array();
  for (size_t s = 0; s < scenes.size(); ++s) {
    for (int im : scenes[s].test) {
      Json views = Json::array();
      for (const BopSensor& sensor : sensors) views.push_back(Json::array({sensor.name, im}));
      targets.push_back({{"scene_id", s}, {"im_id", views}});
    }
  }
  WriteFileAtomic(root / "test_targets_multiview_bop25.json", targets.dump(2) + "\n");
}

}  // namespace cadsynth
