// Assemblies that work: gear pairs, planetary gearboxes, slider-crank mechanisms, built as B-rep
// parts with placements (x_in_assembly = placement * x_in_part).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "cad/part.h"
#include "cad/shape.h"
#include "variants/gear.h"

namespace cadsynth {

// B-rep parts and where each copy sits; tessellate with TessellateAssembly.
struct ShapeAssembly {
  struct Component {
    std::string name;
    Shape shape;
    Symmetries symmetries;  // in the shape's own (CAD) frame
  };
  struct Placement {
    int component = 0;
    std::string name;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  };
  std::string name;
  std::vector<Component> components;
  std::vector<Placement> placements;
};

// Parts (tessellated in parallel, in their model frames) and instances of `assembly`.
Assembly TessellateAssembly(const ShapeAssembly& assembly, const TessellationOptions& options);

// Two external gears in mesh: `first` at the origin, `second` on +x at the working centre
// distance (from the profile shifts), turned so a tooth of the first sits in a space of the
// second. Both need the same module and pressure angle; helical gears need opposite helix angles.
struct GearPairOptions {
  GearOptions first;
  GearOptions second;
  bool Check(std::string* why) const;
  double CentreDistance() const;  // mm
};
ShapeAssembly MakeGearPair(const GearPairOptions& options);

// A planetary gearbox: sun, N planets and the ring (z_ring = z_sun + 2 z_planet), all spur, and a
// carrier plate with one pin per planet under them. Planets are spaced evenly, which needs
// (z_sun + z_ring) / N to be a whole number, and phased so every mesh engages.
struct PlanetaryOptions {
  int sun_teeth = 18;
  int planet_teeth = 18;
  int planets = 3;
  double module_mm = 1.5;
  double face_width_mm = 10.0;
  double backlash_mm = 0.05;  // per gear
  double pin_diameter_mm = 6.0;
  double carrier_thickness_mm = 4.0;
  double sun_bore_mm = 6.0;

  int RingTeeth() const { return sun_teeth + 2 * planet_teeth; }
  double CentreDistance() const { return 0.5 * module_mm * (sun_teeth + planet_teeth); }
  bool Check(std::string* why) const;
};
ShapeAssembly MakePlanetary(const PlanetaryOptions& options);

// Base plate, crank, connecting rod and slider, lying on the base; the crank turns about the
// origin in the xy-plane and the slider runs along +x. Links are flat bars with round ends.
struct SliderCrankOptions {
  double crank_mm = 40.0;  // crank radius (pivot to pin)
  double rod_mm = 120.0;   // connecting rod, pin to pin
  double crank_angle_rad = 0.6;
  double link_width_mm = 16.0;
  double link_thickness_mm = 6.0;
  double pin_diameter_mm = 6.0;
  double slider_mm = 30.0;  // slider block length (x); width = link width + 8 mm
  bool Check(std::string* why) const;
  // Slider pin x position for the crank angle: r cos(t) + sqrt(l^2 - r^2 sin^2(t)).
  double SliderX() const;
};
ShapeAssembly MakeSliderCrank(const SliderCrankOptions& options);

}  // namespace cadsynth
