// Symmetry detection (issue 20): the rotations that map a part's mesh onto itself within a
// tolerance, for parts that declare none (imported STEP and mesh files). BOP's convention:
// discrete rotations as 4 x 4 transforms and continuous rotations about an axis, in the part's
// model frame.
#pragma once

#include <string>
#include <vector>

#include "cad/mesh.h"
#include "cad/part.h"

namespace cadsynth {

struct SymmetryOptions {
  // A point of the surface moved by a symmetry must land within this of the surface (mm). 0:
  // 0.25% of the mesh's bounding-box diagonal plus twice `deviation_mm`.
  double tolerance_mm = 0;
  double deviation_mm = 0;  // the tessellation's distance from the exact surface, when known
  int max_order = 360;      // the largest n-fold rotation looked for
  int max_points = 6000;    // surface points tested (vertices first, then triangle centroids)
  // Lines to test as axes besides those the mesh suggests, in the mesh's frame: the axes of the
  // exact B-rep's surfaces of revolution (RevolutionAxes). A line is tested when it passes
  // within the tolerance of the surface's centroid.
  struct Line {
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
  };
  std::vector<Line> axis_hints;
  bool Check(std::string* why) const;
};

struct DetectedSymmetries {
  Symmetries symmetries;  // in the mesh's frame
  // The largest distance (mm) of a moved surface point from the surface, per discrete symmetry
  // (same order) and per continuous axis (the worst of a few test angles): how exactly each
  // holds, so that a user can judge symmetries that only small details break.
  std::vector<double> discrete_deviation_mm, continuous_deviation_mm;
  // On the exact B-rep, when the part has one (CompareBrepFaces), surface to surface: per
  // discrete symmetry (and per continuous axis, at the test angles) the largest distance between
  // a moved surface and the nearest one like it (the same kind, its faces' area within 0.1%):
  // planes, cylinders, cones, spheres and tori by their exact parameters (all faces on one such
  // surface together), free-form faces by their centroids. Infinite when an analytic surface has
  // no partner within 0.1% of the part's size (a chamfer on one corner). Free-form faces without a
  // partner (split where a file pleases) are not compared, only counted. Empty without a B-rep.
  std::vector<double> discrete_brep_mm, continuous_brep_mm;
  int brep_faces_not_compared = 0;
  double tolerance_mm = 0;  // the tolerance used
  // The rotation axes found (through `centre`) and their orders (0: continuous), main axis first.
  struct Axis {
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
    int order = 0;
  };
  std::vector<Axis> axes;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // the surface's area centroid
};

// The axes of a B-rep's faces of revolution (cylinders, cones, tori, surfaces of revolution),
// exact, in the shape's frame, merged where they are one line and sorted by the area of their
// faces, largest first (at most `max_axes`). Empty for a null shape.
std::vector<SymmetryOptions::Line> RevolutionAxes(const Shape& shape, int max_axes = 8);

// Fills found->discrete_brep_mm and continuous_brep_mm from the part's B-rep (nothing without
// one): the exact check of symmetries found or listed on the mesh. A face OpenCASCADE cannot
// measure leaves both empty.
void CompareBrepFaces(const Part& part, DetectedSymmetries* found);

// The options the pipeline detects a part's symmetries with: its measured tessellation
// deviation, and the axes of revolution of its B-rep (if it has one) in its model frame.
SymmetryOptions PartSymmetryOptions(const Part& part, double tolerance_mm = 0);

// "6-fold about (0, 0, 1) and 6 flips; largest deviation 0.012 mm (tolerance 0.2 mm)": for
// messages and `inspect`.
std::string DescribeSymmetries(const DetectedSymmetries& detected);

// The symmetries of `mesh`: candidate axes through the surface's centroid (its principal axes of
// area and the directions of its largest flat areas), each tested for continuous rotation and
// for n-fold rotation (the largest n up to max_order), half-turns about axes perpendicular to
// the main one (scanned over the angle, then refined), and the group these generate, every
// member checked on the surface points. Deterministic; throws Error for an empty mesh or bad
// options.
DetectedSymmetries DetectSymmetries(const Mesh& mesh, const SymmetryOptions& options = {});

// Symmetries given by a user (a recipe's explicit list), completed to the group they generate
// (every product of the discrete ones) and measured on `mesh` as DetectSymmetries measures its
// own: the deviations say how exactly each holds; nothing is left out. Throws Error for an empty
// mesh or bad options.
DetectedSymmetries MeasureSymmetries(const Mesh& mesh, const Symmetries& given,
                                     const SymmetryOptions& options = {});

}  // namespace cadsynth
