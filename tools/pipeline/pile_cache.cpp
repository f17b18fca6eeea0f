// A pile's simulated result in the part cache (prepare_stages.h): the key holds everything that
// decides it, the value the pile, its pick sequence and the messages they gave.
#include <algorithm>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cad/core/error.h"
#include "cad/part_cache.h"
#include "tools/pipeline/prepare_stages.h"

namespace cadsynth::prepare_stages {
namespace {

void PutInstance(ByteWriter* w, const Instance& instance) {
  w->Put(instance.part);
  w->PutText(instance.name);
  w->Put(Eigen::Matrix4d(instance.world_from_model.matrix()));
  w->Put(instance.color.has_value());
  w->Put(instance.color.value_or(Eigen::Vector3f::Zero()));
  w->PutText(instance.path);
}

Instance GetInstance(ByteReader* r) {
  Instance instance;
  instance.part = r->Get<int>();
  instance.name = r->GetText();
  instance.world_from_model.matrix() = r->Get<Eigen::Matrix4d>();
  const bool has_color = r->Get<bool>();
  const Eigen::Vector3f color = r->Get<Eigen::Vector3f>();
  if (has_color) instance.color = color;
  instance.path = r->GetText();
  return instance;
}

void PutArrangement(ByteWriter* w, const Arrangement& a) {
  for (const std::vector<Instance>* list : {&a.instances, &a.distractors}) {
    w->Put(static_cast<uint64_t>(list->size()));
    for (const Instance& instance : *list) PutInstance(w, instance);
  }
  for (const std::vector<int>* list :
       {&a.group, &a.restless, &a.escaped, &a.restless_distractors, &a.escaped_distractors})
    w->PutArray(*list);
  w->Put(a.settle_seconds);
  w->Put(a.distractor_seconds);
}

Arrangement GetArrangement(ByteReader* r) {
  Arrangement a;
  for (std::vector<Instance>* list : {&a.instances, &a.distractors}) {
    const auto n = r->Get<uint64_t>();
    if (n > (1u << 24)) throw Error("pile cache: damaged");
    for (uint64_t i = 0; i < n; ++i) list->push_back(GetInstance(r));
  }
  for (std::vector<int>* list :
       {&a.group, &a.restless, &a.escaped, &a.restless_distractors, &a.escaped_distractors})
    *list = r->GetArray<int>();
  a.settle_seconds = r->Get<double>();
  a.distractor_seconds = r->Get<double>();
  return a;
}

}  // namespace

std::string EncodePile(const Placement& placement,
                       const std::vector<std::pair<bool, std::string>>& messages) {
  ByteWriter w;
  PutArrangement(&w, placement.arranged);
  w.Put(static_cast<uint64_t>(placement.picks.size()));
  for (size_t k = 0; k < placement.picks.size(); ++k) {
    const PickStep& step = placement.picks[k];
    w.Put(step.picked);
    PutArrangement(&w, step.arranged);
    w.PutArray(std::vector<uint8_t>(step.freed.begin(), step.freed.end()));
    w.PutArray(step.moved_mm);
    w.PutArray(placement.pick_ids[k]);
  }
  w.Put(static_cast<uint64_t>(messages.size()));
  for (const auto& [warning, text] : messages) {
    w.Put(warning);
    w.PutText(text);
  }
  return w.bytes();
}

void DecodePile(std::string_view bytes, Placement* placement,
                std::vector<std::pair<bool, std::string>>* messages) {
  ByteReader r(bytes);
  placement->arranged = GetArrangement(&r);
  const auto picks = r.Get<uint64_t>();
  if (picks > 1000) throw Error("pile cache: damaged");
  placement->picks.clear();
  placement->pick_ids.clear();
  for (uint64_t k = 0; k < picks; ++k) {
    PickStep step;
    step.picked = r.Get<int>();
    step.arranged = GetArrangement(&r);
    const std::vector<uint8_t> freed = r.GetArray<uint8_t>();
    step.freed.assign(freed.begin(), freed.end());
    step.moved_mm = r.GetArray<double>();
    placement->picks.push_back(std::move(step));
    placement->pick_ids.push_back(r.GetArray<int>());
  }
  const auto n = r.Get<uint64_t>();
  if (n > (1u << 20)) throw Error("pile cache: damaged");
  for (uint64_t i = 0; i < n; ++i) {
    const bool warning = r.Get<bool>();
    messages->emplace_back(warning, r.GetText());
  }
}

CacheKey PileKey(const PartCache& cache, const SceneSpec& scene_spec,
                 const std::vector<Part>& parts, const std::vector<Instance>& instances,
                 const std::vector<int>& groups, const ArrangementOptions& a,
                 const CollisionOptions& collision, bool strict) {
  KeyHasher hasher;
  cache.Start(&hasher, "pile 3");
  hasher.Text(scene_spec.name).Value(strict).Fields(collision);
  std::vector<int> used;
  for (const Instance& instance : instances) used.push_back(instance.part);
  used.insert(used.end(), a.distractors.begin(), a.distractors.end());
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  for (int p : used) {
    const Part& part = parts[static_cast<size_t>(p)];
    hasher.Value(p).Text(part.name).Geometry(part.mesh).Value(part.watertight);
    hasher.Value(part.mass.volume_mm3).Value(part.mass.center_of_mass).Value(part.mass.inertia);
  }
  for (size_t i = 0; i < instances.size(); ++i) {
    const Instance& instance = instances[i];
    hasher.Value(instance.part).Text(instance.name).Text(instance.path);
    hasher.Value(Eigen::Matrix4d(instance.world_from_model.matrix()));
    hasher.Value(instance.color.has_value())
        .Value(instance.color.value_or(Eigen::Vector3f::Zero()));
    hasher.Value(i < groups.size() ? groups[i] : -1);
  }
  hasher.Fields(a).Fields(a.container).Fields(a.container.material).Fields(a.sequence);
  hasher.Geometry(a.container.mesh);
  hasher.Fields(a.physics.low).Fields(a.physics.high);
  for (const PhysicsDraw& d : a.part_physics) hasher.Fields(d.low).Fields(d.high);
  for (int d : a.distractors) hasher.Value(d);
  hasher.Value(a.distractor_seed);
  return hasher.Key();
}

}  // namespace cadsynth::prepare_stages
