// How a rigid body comes to rest on a floor: the faces of its convex hull that hold the centre of
// mass above them, and how likely a random drop ends on each.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "cad/hull.h"
#include "cad/part.h"

namespace cadsynth {

struct StablePose {
  Eigen::Vector3d
      normal;  // outward normal of the resting face, in the body frame (points down when resting)
  double probability = 0;  // of a random drop ending on this face (quasi-static solid-angle method)
  double height = 0;       // centre of mass above the floor when resting, mm
  // Faces that rest the body at the same height are one pose up to the body's symmetry (the many
  // flats of a tessellated cylinder's side); their summed probability, and the pose's index.
  double pose_probability = 0;
  int pose = 0;
  // Rotation and lift that put the body on the floor z = 0 resting on this face (yaw 0):
  // x_world = floor_from_body * x_body.
  Eigen::Isometry3d floor_from_body = Eigen::Isometry3d::Identity();
};

// The stable poses of the convex hull of `points` (body frame, mm) with centre of mass `com`:
// faces grouped into poses by resting height, the most probable pose first, faces within a pose in
// a fixed geometric order (so the result does not depend on the hull algorithm's internal order);
// probabilities sum to 1. Coplanar hull triangles form one face. A face is stable
// when the centre of mass projects inside it; the solid angle an unstable face subtends at the
// centre of mass goes to the face it tips onto (over its edge furthest beyond the centre of mass),
// repeatedly, until a stable face is reached. Points in one plane (a sheet) rest on either side
// of it, probability 1/2 each. Throws Error for points that span no area, or are not finite.
// With `symmetries` (body frame), faces at one height are one pose only when a symmetry maps one
// onto the other.
std::vector<StablePose> StablePoses(const std::vector<Eigen::Vector3d>& points,
                                    const Eigen::Vector3d& com,
                                    const Symmetries* symmetries = nullptr);
// The same from the hull itself.
std::vector<StablePose> StablePoses(const ConvexHull& hull, const Eigen::Vector3d& com,
                                    const Symmetries* symmetries = nullptr);

// The stable poses of instances of `parts` taken together as one rigid body (body frame = the
// instances' frame); the centre of mass combines the parts' volumes (or, for open meshes, their
// box centres weighted by surface area). One instance's part's symmetries pool its faces.
std::vector<StablePose> StablePoses(const std::vector<Part>& parts,
                                    const std::vector<Instance>& instances);

}  // namespace cadsynth
