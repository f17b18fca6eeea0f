// Object classes: which semantic class (models_cad.json, the merged COCO's categories) each part
// belongs to, from the recipe's class groups and the families' labels.
#include <fnmatch.h>

#include <map>

#include "dataset/bop.h"

namespace cadsynth {

std::vector<ObjectClass> AssignClasses(
    const std::vector<std::string>& part_names, const std::vector<std::string>& labels,
    const std::vector<std::pair<std::string, std::vector<std::string>>>& groups,
    std::vector<std::string>* empty_groups) {
  std::vector<ObjectClass> classes(part_names.size());
  std::vector<bool> used(groups.size(), false);
  int next_id = static_cast<int>(groups.size()) + 1;
  std::map<std::string, int> label_ids;
  for (size_t i = 0; i < part_names.size(); ++i) {
    if (i < labels.size() && !labels[i].empty()) {
      auto [it, inserted] = label_ids.emplace(labels[i], next_id);
      if (inserted) ++next_id;
      classes[i] = {it->second, labels[i]};
      continue;
    }
    for (size_t g = 0; g < groups.size() && classes[i].id == 0; ++g) {
      for (const std::string& pattern : groups[g].second) {
        if (fnmatch(pattern.c_str(), part_names[i].c_str(), FNM_CASEFOLD) == 0) {
          classes[i] = {static_cast<int>(g) + 1, groups[g].first};
          used[g] = true;
          break;
        }
      }
    }
    if (classes[i].id == 0) classes[i] = {next_id++, part_names[i]};
  }
  empty_groups->clear();
  for (size_t g = 0; g < groups.size(); ++g) {
    if (!used[g]) empty_groups->push_back(groups[g].first);
  }
  return classes;
}

}  // namespace cadsynth
