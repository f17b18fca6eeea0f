// Parts (distinct shapes, each one object class of the dataset) and their instances.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "cad/brep.h"
#include "cad/hull.h"
#include "cad/mesh.h"

namespace cadsynth {

// Mass properties of a solid with unit density, in the frame its geometry is given in.
struct MassProperties {
  double volume_mm3 = 0.0;
  Eigen::Vector3d center_of_mass = Eigen::Vector3d::Zero();  // mm
  // Inertia tensor about the centre of mass, axes of the same frame, for density 1 (mm^5).
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

// The rigid motions that map a shape onto itself (BOP's symmetries_discrete and
// symmetries_continuous), in the frame the shape is given in: x' = transform * x.
struct Symmetries {
  std::vector<Eigen::Isometry3d> discrete;  // without the identity
  struct Axis {
    Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();      // a point on the axis
  };
  std::vector<Axis> continuous;  // any rotation about these axes
  bool empty() const { return discrete.empty() && continuous.empty(); }
  // The same symmetries seen in another frame: for x_old = old_from_new * x_new.
  Symmetries InFrame(const Eigen::Isometry3d& old_from_new) const;
  // Common cases, about the z axis through the origin: an n-fold rotation, optionally with the
  // n half-turns about horizontal axes that flip the shape over (for shapes symmetric top to
  // bottom about `mid_z`), the first at `flip_angle` from +x; continuous rotation about z,
  // optionally with a flip about x.
  static Symmetries Cyclic(int n, bool flips, double mid_z = 0.0, double flip_angle = 0.0);
  static Symmetries Revolution(bool flip, double mid_z = 0.0);
};

// One distinct shape. Its model frame is its CAD frame moved to the centre of the axis-aligned
// bounding box of the mesh (BOP practice); `cad_from_model` keeps that offset, so a point moves
// as x_in_cad = cad_from_model * x_in_model. Mesh and mass properties are in the model frame.
struct Part {
  std::string name;
  Mesh mesh;
  Eigen::Isometry3d cad_from_model = Eigen::Isometry3d::Identity();
  MassProperties mass;
  bool mass_from_brep = false;  // true when `mass` came from the exact B-rep
  bool watertight = false;      // the mesh is closed and consistently wound
  // Largest measured distance between the mesh and the exact B-rep surface (mm); negative when
  // not measured or there is no B-rep.
  double max_deviation_mm = -1.0;
  std::optional<Eigen::Vector3f> color;  // sRGB in [0, 1], when the CAD file gives one
  Symmetries symmetries;                 // in the model frame; empty when unknown
  Shape brep;  // the exact solid in the CAD frame (null for meshes), for scaling and export
  // The convex hull of mesh.positions, once computed (the run's prepare stage fills it, from the
  // part cache where it can); null otherwise, and whoever needs it computes it. Whoever moves the
  // mesh's vertices resets it.
  std::shared_ptr<const ConvexHull> hull;
};

// One placed copy of a part. A point of the part moves to the world (or to the frame of the
// assembly it belongs to) as x_in_world = world_from_model * x_in_model.
struct Instance {
  int part = 0;      // index into the owning list of parts
  std::string name;  // instance name from the CAD file, or generated
  Eigen::Isometry3d world_from_model = Eigen::Isometry3d::Identity();
  std::optional<Eigen::Vector3f> color;  // overrides the part's colour for this instance
  // Where it sits in the file's assembly tree: names from the root down, joined by '/'.
  std::string path;
};

// An assembly as read from a file: distinct parts, and every instance placed in the frame of the
// file's root (a part used N times is one Part with N Instances).
struct Assembly {
  std::string name;
  std::string format;       // "STEP", "IGES", "BREP", "mesh (stl)", "built-in", ...
  std::string length_unit;  // the length unit the file declares (geometry is in mm regardless)
  std::vector<Part> parts;
  std::vector<Instance> instances;
};

}  // namespace cadsynth
