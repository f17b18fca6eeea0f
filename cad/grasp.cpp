#include "cad/grasp.h"

#include <cmath>

namespace cadsynth {

bool ParallelJawGripper::Check(std::string* why) const {
  if (!(max_opening_mm > 0 && max_opening_mm < 1000)) {
    *why = "max_opening must lie in (0, 1000) mm";
  } else if (!(finger_width_mm > 0) || !(finger_thickness_mm > 0) || !(finger_length_mm > 0) ||
             finger_width_mm > 1000 || finger_thickness_mm > 1000 || finger_length_mm > 1000) {
    *why = "finger width, thickness and length must lie in (0, 1000] mm";
  } else if (!(palm_height_mm >= 0) || !(palm_width_mm >= 0) || !(palm_depth_mm >= 0) ||
             palm_height_mm > 1000 || palm_width_mm > 1000 || palm_depth_mm > 1000) {
    *why = "palm sizes must lie in [0, 1000] mm";
  } else if (!(pad_mm >= 0 && pad_mm <= finger_length_mm)) {
    *why = "pad must lie on the finger (0 to finger_length below the tip)";
  } else {
    return true;
  }
  return false;
}

ParallelJawGripper ParallelJawGripper::Franka() { return ParallelJawGripper{}; }

ParallelJawGripper ParallelJawGripper::Robotiq2F85() {
  ParallelJawGripper g;
  g.name = "robotiq_2f85";
  g.max_opening_mm = 85.0;
  g.finger_width_mm = 22.0;
  g.finger_thickness_mm = 12.0;
  g.finger_length_mm = 63.0;
  g.palm_height_mm = 100.0;
  g.palm_width_mm = 110.0;
  g.palm_depth_mm = 76.0;
  g.pad_mm = 8.0;
  return g;
}

bool SuctionCup::Check(std::string* why) const {
  if (!(diameter_mm > 0 && diameter_mm <= 500)) {
    *why = "diameter must lie in (0, 500] mm";
  } else if (ring_points < 3 || ring_points > 360) {
    *why = "ring_points must be 3 to 360";
  } else if (!(compliance_mm > 0 && compliance_mm <= diameter_mm)) {
    *why = "compliance must lie in (0, diameter] mm";
  } else if (!(stretch > 0 && stretch <= 1)) {
    *why = "stretch must lie in (0, 1]";
  } else if (!(vacuum_kpa > 0 && vacuum_kpa <= 101.325)) {
    *why = "vacuum must lie in (0, 101.325] kPa (a pressure difference below one atmosphere)";
  } else if (!(cup_length_mm > 0 && cup_length_mm <= 1000) ||
             !(shaft_length_mm >= 0 && shaft_length_mm <= 2000) ||
             !(shaft_diameter_mm > 0 && shaft_diameter_mm <= 500)) {
    *why = "cup_length and shaft_diameter must lie in (0, 1000] mm, shaft_length in [0, 2000]";
  } else {
    return true;
  }
  return false;
}

double SuctionCup::vacuum_force_n() const {
  const double a = 0.5e-3 * diameter_mm;  // m
  return vacuum_kpa * 1e3 * M_PI * a * a;
}

}  // namespace cadsynth
