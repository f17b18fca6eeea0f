// Placing parts as they would rest in a work cell: on the floor z = 0, centred on the origin.
#pragma once

#include <string>
#include <vector>

#include "cad/part.h"

namespace cadsynth {

enum class Layout {
  kAssembled,  // the instances as designed, moved as one rigid body onto the floor
  kRow,        // every instance on its own, in its CAD orientation, side by side along +x
};

struct ArrangementOptions {
  Layout layout = Layout::kAssembled;
  double gap_mm = 40.0;  // kRow: free space between neighbouring instances

  bool Check(std::string* why) const;
};

// Returns `instances` with world poses such that the lowest point of the arrangement is on the
// floor (z = 0) and its bounding box is centred on the world z axis. Each instance keeps its part
// index and name. `parts` gives the meshes the instances refer to.
std::vector<Instance> Arrange(const std::vector<Part>& parts, const std::vector<Instance>& instances,
                              const ArrangementOptions& options);

}  // namespace cadsynth
