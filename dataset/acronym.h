// Per-object grasp files as ACRONYM writes them (NVlabs/acronym, HDF5 through Debian's libhdf5):
// what grasp networks trained on ACRONYM (6-DOF GraspNet, Contact-GraspNet) read.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace cadsynth {

// One object's grasps. Transforms are model_from_gripper in the object's model frame (mm; the
// file holds metres), in ACRONYM's gripper frame: origin at the hand's base, +z the approach,
// the fingers closing along x.
struct AcronymGrasps {
  std::string object_file;     // the mesh, relative to the dataset (e.g. models/obj_000001.ply)
  double object_scale = 1e-3;  // the mesh's units to metres (BOP models are in mm)
  std::string gripper = "panda";
  double gripper_configuration = 0.04;  // ACRONYM's: half the opening, in metres
  std::vector<Eigen::Isometry3d> model_from_gripper;
  std::vector<double> width_mm;  // the contacts' distance
  std::vector<double> quality;   // force-closure margin in [0, 1]
  std::vector<int> success;      // 1: a grasp (every grasp we keep holds by force closure)
  // The object's physics, as ACRONYM records it (SI units): mass (kg), centre of mass (m) in the
  // model frame, density (kg/m^3), friction, volume (m^3).
  double mass_kg = 0, density = 0, friction = 0, volume_m3 = 0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  // Suction grasps, in cadsynth's own group beside ACRONYM's (written when the cup's diameter is
  // above 0): contact points (model frame, mm; the file holds metres), approach directions (unit,
  // into the surface), seal and wrench scores (cad/grasp.h), and the cup.
  std::vector<Eigen::Vector3d> suction_points_mm, suction_approaches;
  std::vector<double> suction_seal, suction_wrench;
  double cup_diameter_mm = 0, cup_vacuum_kpa = 0;
};

// Writes `grasps` to `path` in ACRONYM's layout:
//   grasps/transforms (N, 4, 4) float64, metres;
//   grasps/qualities/flex/object_in_gripper (N,) int64 (our success labels);
//   grasps/qualities/cadsynth/force_closure (N,) float64; grasps/widths (N,) float64, metres;
//   gripper/type (string), gripper/configuration (1,) float64;
//   object/file (string), object/scale, object/friction, object/volume float64 scalars,
//   object/com (3,) float64, and object/mass, object/density when they are above 0 (known);
//   with a cup: suction/points (M, 3) and suction/approaches (M, 3) float64 (metres, unit),
//   suction/qualities/seal, suction/qualities/wrench, suction/qualities/score (seal x wrench)
//   (M,) float64, suction/cup_diameter (m) and suction/vacuum (Pa) scalars.
// Throws Error naming the file when it cannot be written or the arrays disagree in length.
void WriteAcronymFile(const std::filesystem::path& path, const AcronymGrasps& grasps);

// Reads back what WriteAcronymFile wrote (transforms in mm), for tests and tools.
AcronymGrasps ReadAcronymFile(const std::filesystem::path& path);

}  // namespace cadsynth
