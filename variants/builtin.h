// Parts cadsynth builds by itself, so the default job needs no input files.
#pragma once

#include <string>

#include "cad/part.h"
#include "cad/shape.h"

namespace cadsynth {

// A spur-gear blank: a prism over a toothed outline (straight-sided trapezoidal teeth, a
// placeholder for the involute gears of the variant families) with a round bore. Axis +z, base
// on z = 0, centred on the axis. All lengths in mm.
struct GearBlankOptions {
  int teeth = 20;
  double module_mm = 3.0;        // pitch diameter = module * teeth
  double face_width_mm = 15.0;   // along the axis
  double bore_diameter_mm = 12.0;

  bool Check(std::string* why) const;
  double TipRadius() const { return 0.5 * module_mm * (teeth + 2); }
  double RootRadius() const { return 0.5 * module_mm * (teeth - 2.5); }
};
Shape MakeGearBlank(const GearBlankOptions& options);

// The default set: a box (80 x 60 x 40 mm), a round peg (diameter 30 mm, 80 mm tall, standing)
// and the default gear blank. One instance each, at the CAD origin (arrange them afterwards).
Assembly MakeDefaultParts(const TessellationOptions& tessellation);

}  // namespace cadsynth
