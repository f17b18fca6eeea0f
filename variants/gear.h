// Involute gears as exact B-rep solids.
//
// Conventions: the gear axis is +z, the gear sits on z = 0 and extends to z = face_width (a hub
// continues below z = 0). Tooth 0 is centred on the +x axis (for internal gears: tooth 0 of the
// ring points inward along +x). Lengths in mm, angles in radians.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "cad/shape.h"

namespace cadsynth {

struct GearOptions {
  int teeth = 20;
  double module_mm = 2.0;                                             // normal module
  double pressure_angle_rad = 20.0 * 3.14159265358979323846 / 180.0;  // normal pressure angle
  double face_width_mm = 10.0;
  double profile_shift = 0.0;     // x, in modules (positive: thicker teeth, larger tip)
  double backlash_mm = 0.0;       // tooth thinned by this much at the pitch circle
  double root_fillet = 0.38;      // fillet radius in modules (basic rack: 0.38)
  double helix_angle_rad = 0.0;   // 0: spur; positive: right hand
  bool internal = false;          // a ring gear with teeth pointing inward
  double rim_width_mm = 0.0;      // internal: ring wall beyond the root circle (0: 2.5 modules)
  double bore_diameter_mm = 0.0;  // external: centre hole (0: none)
  double hub_diameter_mm = 0.0;   // external: hub below the gear (0: none)
  double hub_length_mm = 0.0;

  // False with a reason for impossible gears (too few teeth, a bore beyond the root circle,
  // pointed teeth, ...).
  bool Check(std::string* why) const;

  double TransverseModule() const;
  double TransversePressureAngle() const;
  double PitchRadius() const;  // m_t z / 2
  double BaseRadius() const;   // pitch radius times cos(transverse pressure angle)
  // External: pitch + m (1 + x) and pitch - m (1.25 - x). Internal (ring): tip is the inner
  // circle, pitch - m (1 - x); root the outer, pitch + m (1.25 + x).
  double TipRadius() const;
  double RootRadius() const;
  double FilletRadius() const;  // the fillet radius used (reduced to fit the tooth space)
};

// The transverse outline of an external gear (or, for an internal gear, of the cutter whose teeth
// are the ring's tooth spaces) as a closed polygon, counter-clockwise, `per_segment` points on
// each curved piece. For tests and previews; the B-rep uses the same curves exactly.
std::vector<Eigen::Vector2d> GearOutline(const GearOptions& options, int per_segment);

// The involute function inv(alpha) = tan(alpha) - alpha (alpha in radians): the polar angle of
// the involute of a circle at the point where its pressure angle is alpha.
inline double Involute(double alpha) { return std::tan(alpha) - alpha; }

// Largest distance (mm) between the B-spline the B-rep uses for a flank and the exact involute,
// measured at 2000 points.
double InvoluteFitError(const GearOptions& options);

// The gear solid. Throws Error (with the reason) for impossible parameters.
Shape MakeGear(const GearOptions& options);

// Its symmetries: z-fold about the axis, and for gears without a hub (spur or helical) the z
// half-turns that turn it over (CAD frame).
Symmetries GearSymmetries(const GearOptions& options);

}  // namespace cadsynth
