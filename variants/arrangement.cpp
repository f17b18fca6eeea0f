#include "variants/arrangement.h"

#include "cad/error.h"

namespace cadsynth {

bool ArrangementOptions::Check(std::string* why) const {
  if (!(gap_mm >= 0.0)) {
    *why = "gap must not be negative";
    return false;
  }
  return true;
}

namespace {

Eigen::AlignedBox3d InstanceBounds(const std::vector<Part>& parts, const Instance& instance) {
  return parts.at(instance.part).mesh.Bounds(instance.world_from_model);
}

// Moves every instance by the same translation so that `box` rests on z = 0, centred in x and y.
void PlaceOnFloor(const Eigen::AlignedBox3d& box, std::vector<Instance>* instances) {
  const Eigen::Vector3d shift(-box.center().x(), -box.center().y(), -box.min().z());
  for (Instance& instance : *instances) {
    instance.world_from_model = Eigen::Translation3d(shift) * instance.world_from_model;
  }
}

}  // namespace

std::vector<Instance> Arrange(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                              const ArrangementOptions& options) {
  std::string why;
  if (!options.Check(&why)) throw Error("arrangement: " + why);
  for (const Instance& instance : instances) {
    if (instance.part < 0 || static_cast<size_t>(instance.part) >= parts.size()) {
      throw Error("arrangement: instance '" + instance.name + "' refers to a missing part");
    }
  }
  std::vector<Instance> placed = instances;
  if (placed.empty()) return placed;

  if (options.layout == Layout::kRow) {
    double x = 0.0;
    for (Instance& instance : placed) {
      const Eigen::AlignedBox3d box = InstanceBounds(parts, instance);
      const Eigen::Vector3d shift(x - box.min().x(), -box.center().y(), -box.min().z());
      instance.world_from_model = Eigen::Translation3d(shift) * instance.world_from_model;
      x += box.sizes().x() + options.gap_mm;
    }
  }
  Eigen::AlignedBox3d all;
  for (const Instance& instance : placed) all.extend(InstanceBounds(parts, instance));
  PlaceOnFloor(all, &placed);
  return placed;
}

}  // namespace cadsynth
