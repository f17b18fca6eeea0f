// Standard parts as B-rep solids, with their symmetries. Axis +z, base on z = 0, centred on the
// z axis unless stated. Lengths in mm. Threads are not modelled (plain cylinders at the nominal
// diameter).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "variants/mechanisms.h"

namespace cadsynth {

// ISO metric sizes M3 to M24: hex bolts (ISO 4017), nuts (ISO 4032), washers (ISO 7089).
struct MetricSize {
  std::string name;  // "M8"
  double d;          // nominal diameter
  double s;          // width across flats (bolt head and nut)
  double k;          // bolt head height
  double m;          // nut height
  double washer_inner, washer_outer, washer_thickness;
};
// Throws Error listing the known sizes for an unknown one.
const MetricSize& IsoMetric(const std::string& name);
std::vector<std::string> IsoMetricSizes();

// Shoulder bolts (ISO 7379) by shoulder diameter 6, 8, 10, 12, 16, 20 mm.
struct ShoulderSize {
  double shoulder_d, thread_d, thread_length, head_d, head_k, socket_s;
};
const ShoulderSize& IsoShoulder(double shoulder_d);

using Component = ShapeAssembly::Component;

Component MakeRoundPeg(double diameter, double length);
Component MakeSquarePeg(double side, double length);
// An open-top box housing like a gearbox's lower casing (the reference paper's): outer length
// (along x) x width x height, walls and floor `wall` thick, and a half-round bearing seat of
// `seat_diameter` (0: none) cut into each end wall, its axis along x on the top edge. Concave and
// closed: piles decompose it.
Component MakeCasing(double length, double width, double height, double wall, double seat_diameter);
// A rectangular plate centred on the origin with a rows x columns grid of through holes, its
// outer holes `margin` from the edges.
Component MakeFaceplate(double width, double height, double thickness, int rows, int columns,
                        double hole_diameter, double margin);
// Cylinders of the given (diameter, length) one after another along +z.
Component MakeSteppedShaft(const std::vector<std::pair<double, double>>& sections);
// Head (with hex socket) on z = 0..k pointing down the z axis: head, shoulder, thread.
Component MakeShoulderBolt(double shoulder_d, double shoulder_length);
Component MakeHexBolt(const std::string& size, double length);  // length under the head
Component MakeHexNut(const std::string& size);
Component MakeWasher(const std::string& size);
// A deep-groove ball bearing: inner ring (bore d), outer ring (outer diameter D), width B, and as
// many balls as fit on the pitch circle. One part holding all its solids.
Component MakeBallBearing(double bore, double outer, double width);

}  // namespace cadsynth
