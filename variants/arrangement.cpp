#include "variants/arrangement.h"

#include <algorithm>
#include <cmath>
#include <map>

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

void Shift(const Eigen::Vector3d& shift, Instance* instance) {
  instance->world_from_model = Eigen::Translation3d(shift) * instance->world_from_model;
}

}  // namespace

std::vector<Instance> Arrange(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                              const ArrangementOptions& options, const std::vector<int>& group) {
  std::string why;
  if (!options.Check(&why)) throw Error("arrangement: " + why);
  if (!group.empty() && group.size() != instances.size()) throw Error("arrangement: one group per instance");
  for (const Instance& instance : instances) {
    if (instance.part < 0 || static_cast<size_t>(instance.part) >= parts.size()) {
      throw Error("arrangement: instance '" + instance.name + "' refers to a missing part");
    }
  }
  std::vector<Instance> placed = instances;
  if (placed.empty()) return placed;

  // Groups in order of first appearance, with their bounds.
  std::map<int, size_t> index_of;
  std::vector<std::vector<size_t>> members;
  for (size_t i = 0; i < placed.size(); ++i) {
    const int g = group.empty() ? static_cast<int>(i) : group[i];
    auto [it, inserted] = index_of.emplace(g, members.size());
    if (inserted) members.emplace_back();
    members[it->second].push_back(i);
  }
  std::vector<Eigen::AlignedBox3d> bounds(members.size());
  for (size_t g = 0; g < members.size(); ++g) {
    for (size_t i : members[g]) bounds[g].extend(InstanceBounds(parts, placed[i]));
  }

  if (options.layout != Layout::kAssembled) {
    // Cells: a row, or rows of about sqrt(N); each group centred in its cell, resting on z = 0.
    const size_t n = members.size();
    const size_t columns = options.layout == Layout::kRow ? n : static_cast<size_t>(std::ceil(std::sqrt(double(n))));
    std::vector<double> column_width(columns, 0.0), row_depth((n + columns - 1) / columns, 0.0);
    for (size_t g = 0; g < n; ++g) {
      column_width[g % columns] = std::max(column_width[g % columns], bounds[g].sizes().x());
      row_depth[g / columns] = std::max(row_depth[g / columns], bounds[g].sizes().y());
    }
    for (size_t g = 0; g < n; ++g) {
      double x = 0, y = 0;
      for (size_t c = 0; c < g % columns; ++c) x += column_width[c] + options.gap_mm;
      for (size_t r = 0; r < g / columns; ++r) y -= row_depth[r] + options.gap_mm;
      const Eigen::Vector3d centre(x + 0.5 * column_width[g % columns], y - 0.5 * row_depth[g / columns], 0.0);
      const Eigen::Vector3d shift(centre.x() - bounds[g].center().x(), centre.y() - bounds[g].center().y(),
                                  -bounds[g].min().z());
      for (size_t i : members[g]) Shift(shift, &placed[i]);
    }
  }
  Eigen::AlignedBox3d all;
  for (const Instance& instance : placed) all.extend(InstanceBounds(parts, instance));
  const Eigen::Vector3d shift(-all.center().x(), -all.center().y(), -all.min().z());
  for (Instance& instance : placed) Shift(shift, &instance);
  return placed;
}

}  // namespace cadsynth
