// Gears recognised in imported parts (issue 20): tooth count, module, pressure angle, helix, face
// width and bore measured on the mesh's transverse sections, with the flanks' deviation from the
// ideal involute, so that `inspect` can report them and `family: from_file` can rebuild the gear
// with other teeth, modules or face widths.
//
// The conventions are those of ISO 53's basic rack, as the spur_gear family builds gears: whole
// depth 2.25 normal modules (addendum 1 + x, dedendum 1.25 - x), twist per mm tan(helix) / r_p.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/mesh.h"
#include "cad/symmetry.h"

namespace cadsynth {

struct RecognizedGear {
  int teeth = 0;
  bool internal = false;  // a ring gear, teeth pointing inward
  double module_mm = 0;   // normal module: whole depth / 2.25
  double transverse_module_mm = 0;
  double pressure_angle_rad = 0;  // normal, from the flanks' base circle
  double transverse_pressure_angle_rad = 0;
  // Right hand positive, as the spur_gear family's helix_angle. A herringbone (double helical)
  // gear's lower half (along `axis`) has this helix, its upper half the opposite.
  double helix_angle_rad = 0;
  bool herringbone = false;
  double profile_shift = 0;  // x, in normal modules, from the tip radius
  double tip_radius_mm = 0, root_radius_mm = 0, base_radius_mm = 0, pitch_radius_mm = 0;
  double face_width_mm = 0;
  double bore_diameter_mm = 0;  // the round hole at mid-face (0: none, or not round)
  // Largest distance (mm, along the flank's normal in the transverse plane) of a flank vertex from
  // the fitted involute: how much the file's flanks are involutes.
  double involute_deviation_mm = 0;
  // Where it is, in the mesh's frame: the axis through `centre` (a point on the axis at the
  // toothed band's lower end, h = 0), direction `axis`; `reference` a unit vector perpendicular
  // to it along which the middle of tooth 0 (internal: of tooth space 0) lies at h = 0.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d reference = Eigen::Vector3d::UnitX();
};

// Recognises a gear on `mesh` about one of the candidate axes (lines in the mesh's frame; the
// symmetry's main axis and the B-rep's axes of revolution are good ones). Empty when none of
// them carries involute teeth: at least 5 teeth on the outer (external) or inner (internal)
// outline, a tooth depth between 0.3 and 1.2 of the circular pitch at the tip (a hexagon's
// corners are far shallower), and flank vertices within 0.05 modules (RMS) of an involute.
std::optional<RecognizedGear> RecognizeGear(const Mesh& mesh,
                                            const std::vector<SymmetryOptions::Line>& axes);

// The candidate axes for a part: its detected main axis (when it has one) and its B-rep's axes
// of revolution (PartSymmetryOptions), then RecognizeGear.
std::optional<RecognizedGear> RecognizePartGear(const Part& part, const DetectedSymmetries& found);

// "spur, 20 teeth, module 2 mm, pressure angle 20 deg, ..." for messages and `inspect`.
std::string DescribeGear(const RecognizedGear& gear);

}  // namespace cadsynth
