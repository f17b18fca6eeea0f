// A user's own gear as a family (issue 20, `family: from_file`): the gear recognised in a CAD
// file (cad/gear_recognition.h) rebuilt with other teeth, modules or face widths, its hub, web and
// bore kept as the file has them.
#pragma once

#include <string>

#include "cad/gear_recognition.h"
#include "cad/part.h"

namespace cadsynth {

// What changes; 0 keeps the recognised value.
struct GearRebuild {
  int teeth = 0;
  double module_mm = 0;      // normal module
  double face_width_mm = 0;  // centred on the file's toothed band
};

// The gear's part with its teeth rebuilt, in the part's CAD frame. The file's teeth (its body
// outside the smaller of the old and the new root circle, less a quarter module, along the
// toothed band) are cut off and everything else is kept as the file has it (hub, web, bore, a
// flange beside the band); the new toothed ring is an involute gear of the spur_gear family (the
// recognised pressure angle, helix and profile shift; standard pressure angles within 0.5% and
// shifts under 0.01 snapped), centred on the old band.
// Throws Error with the reason: no B-rep (a mesh file), a herringbone or internal gear, impossible
// teeth, or a root circle that leaves no wall around the bore.
Shape RebuildGear(const Part& part, const RecognizedGear& gear, const GearRebuild& change);

}  // namespace cadsynth
