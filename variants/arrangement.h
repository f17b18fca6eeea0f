// Placing parts as they would rest in a work cell: on the floor z = 0, centred on the origin.
#pragma once

#include <string>
#include <vector>

#include "cad/part.h"

namespace cadsynth {

// Instances come in rigid groups (a file's assembly, one variant of a family): a layout moves
// whole groups and never takes one apart.
enum class Layout {
  kAssembled,  // the groups as designed, in their own frames, moved together onto the floor
  kRow,        // each group on the floor on its own, side by side along +x
  kGrid,       // each group on the floor on its own, in rows of about sqrt(N)
};

struct ArrangementOptions {
  Layout layout = Layout::kAssembled;
  double gap_mm = 40.0;  // kRow, kGrid: free space between neighbouring groups

  bool Check(std::string* why) const;
};

// Returns `instances` with world poses such that the lowest point of each group (kRow, kGrid) or
// of everything (kAssembled) is on the floor z = 0 and the arrangement's bounding box is centred
// on the world z axis. `group[i]` is the group of instance i (empty: one group per instance).
std::vector<Instance> Arrange(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                              const ArrangementOptions& options, const std::vector<int>& group = {});

}  // namespace cadsynth
