#include "variants/stable_pose.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <optional>

#include "cad/core/error.h"

namespace cadsynth {
namespace {

// Solid angle of triangle (a, b, c) seen from the origin (Van Oosterom and Strackee).
double SolidAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double numerator = a.dot(b.cross(c));
  const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
  return std::abs(2.0 * std::atan2(numerator, denominator));
}

struct Face {
  Eigen::Vector3d normal;
  double offset = 0;                         // normal . x = offset on the face plane
  std::map<std::pair<int, int>, int> edges;  // boundary edge (vertex ids) -> neighbouring face
  double solid_angle = 0;
};

}  // namespace

namespace {

// A flat body (a sheet, a planar mesh) rests on either side of its plane, each with probability
// 1/2; nothing when the points do not span a plane (then the hull's error stands).
std::vector<StablePose> FlatPoses(const std::vector<Eigen::Vector3d>& points,
                                  const Eigen::Vector3d& com) {
  if (points.empty()) return {};
  for (const Eigen::Vector3d& p : points) {
    if (!p.allFinite()) return {};
  }
  const Eigen::Vector3d a = points[0];
  Eigen::Vector3d b = a;
  for (const Eigen::Vector3d& p : points) {
    if ((p - a).squaredNorm() > (b - a).squaredNorm()) b = p;
  }
  const Eigen::Vector3d ab = b - a;
  if (ab.squaredNorm() == 0) return {};
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d n = ab.cross(p - a);
    if (n.squaredNorm() > normal.squaredNorm()) normal = n;
  }
  const double size = ab.norm();
  if (!(normal.norm() > 1e-12 * size * size)) return {};  // collinear: no area to rest on
  normal.normalize();
  // Flat up to float rounding (mesh coordinates are floats: a tilted plane's vertices leave it
  // by ~1e-7 of the size); a real sheet is thousands of times thicker than this.
  for (const Eigen::Vector3d& p : points) {
    if (std::abs(normal.dot(p - a)) > 1e-6 * size) return {};  // not flat
  }
  // A fixed side first: the normal whose largest component is positive.
  int axis = 0;
  normal.cwiseAbs().maxCoeff(&axis);
  if (normal[axis] < 0) normal = -normal;
  std::vector<StablePose> poses;
  for (const double side : {1.0, -1.0}) {
    StablePose pose;
    pose.normal = side * normal;
    pose.probability = 0.5;
    pose.pose_probability = 0.5;
    pose.pose = static_cast<int>(poses.size());
    const double offset = pose.normal.dot(a);
    pose.height = offset - pose.normal.dot(com);
    pose.floor_from_body.linear() =
        Eigen::Quaterniond::FromTwoVectors(pose.normal, -Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    pose.floor_from_body.translation() = Eigen::Vector3d(0, 0, offset);
    poses.push_back(pose);
  }
  return poses;
}

// Whether a symmetry turns the normal `a` into `b` (body frame; within 1e-3: a facet's normal
// is exact to far better, distinct faces differ by far more). About a continuous axis any
// normal with the same component along it is reached, after any of the discrete turns.
bool SameUpToSymmetry(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Symmetries& s) {
  constexpr double kWithin = 1e-3;
  std::vector<Eigen::Vector3d> images = {a};
  for (const Eigen::Isometry3d& t : s.discrete) images.push_back(t.linear() * a);
  for (const Eigen::Vector3d& n : images) {
    if ((n - b).norm() < kWithin) return true;
    for (const Symmetries::Axis& axis : s.continuous) {
      const Eigen::Vector3d d = axis.direction.normalized();
      if (std::abs(n.dot(d) - b.dot(d)) < kWithin) return true;
    }
  }
  return false;
}

}  // namespace

std::vector<StablePose> StablePoses(const std::vector<Eigen::Vector3d>& points,
                                    const Eigen::Vector3d& com, const Symmetries* symmetries) {
  if (std::vector<StablePose> flat = FlatPoses(points, com); !flat.empty()) return flat;
  try {
    return StablePoses(ComputeConvexHull(points, /*diameter=*/false), com, symmetries);
  } catch (const Error&) {
    std::vector<StablePose> flat = FlatPoses(points, com);
    if (flat.empty()) throw;
    return flat;
  }
}

namespace {

// A hull's triangles grouped into planar faces.
struct HullFaces {
  std::vector<std::array<int, 3>> neighbour;  // the triangle across each edge of each triangle
  std::vector<int> face_of;                   // each triangle's face
  std::vector<Face> faces;
};

std::array<Eigen::Vector3d, 3> Triangle(const ConvexHull& hull, size_t t) {
  const auto& c = hull.triangles[t];
  return std::array<Eigen::Vector3d, 3>{hull.vertices[c[0]], hull.vertices[c[1]],
                                        hull.vertices[c[2]]};
}

// The triangle across each edge: directed edge (a, b) of one triangle is (b, a) of its
// neighbour. Edges sorted once, looked up by binary search.
std::vector<std::array<int, 3>> Neighbours(const ConvexHull& hull) {
  const size_t n_triangles = hull.triangles.size();
  struct Edge {
    int a, b, triangle;
    bool operator<(const Edge& o) const { return a != o.a ? a < o.a : b < o.b; }
  };
  std::vector<Edge> edges;
  edges.reserve(3 * n_triangles);
  for (size_t t = 0; t < n_triangles; ++t) {
    const auto& c = hull.triangles[t];
    for (int k = 0; k < 3; ++k) edges.push_back({c[k], c[(k + 1) % 3], static_cast<int>(t)});
  }
  std::sort(edges.begin(), edges.end());
  const auto across = [&](int a, int b) {  // the triangle on the other side of edge a -> b
    const auto it = std::lower_bound(edges.begin(), edges.end(), Edge{b, a, 0});
    if (it == edges.end() || it->a != b || it->b != a)
      throw Error("stable poses: the convex hull is not closed");
    return it->triangle;
  };
  std::vector<std::array<int, 3>> neighbour(n_triangles);
  for (size_t t = 0; t < n_triangles; ++t) {
    const auto& c = hull.triangles[t];
    for (int k = 0; k < 3; ++k) neighbour[t][k] = across(c[k], c[(k + 1) % 3]);
  }
  return neighbour;
}

// Group hull triangles into planar faces. A face is grown from its first triangle (in the
// hull's order) over neighbouring triangles in that triangle's plane: a convex polytope's facet
// is connected, so this finds the triangles a search of every face would, in time linear in the
// hull's size.
void GroupFaces(const ConvexHull& hull, double size, HullFaces* h) {
  const size_t n_triangles = hull.triangles.size();
  std::vector<int>& face_of = h->face_of;
  std::vector<Face>& faces = h->faces;
  face_of.assign(n_triangles, -1);
  std::vector<Eigen::Vector3d> normal_of(n_triangles);
  for (size_t t = 0; t < n_triangles; ++t) {
    const auto v = Triangle(hull, t);
    normal_of[t] = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
  }
  std::vector<int> stack;
  for (size_t seed = 0; seed < n_triangles; ++seed) {
    if (face_of[seed] >= 0) continue;
    const int found = static_cast<int>(faces.size());
    const Eigen::Vector3d n = normal_of[seed];
    faces.push_back(Face{n, n.dot(Triangle(hull, seed)[0]), {}, 0});
    face_of[seed] = found;
    stack.assign(1, static_cast<int>(seed));
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      for (int g : h->neighbour[f]) {
        if (face_of[g] >= 0) continue;
        const auto t = Triangle(hull, g);
        if (faces[found].normal.dot(normal_of[g]) > 1 - 1e-9 &&
            std::abs(normal_of[g].dot(t[0]) - faces[found].offset) < 1e-7 * size) {
          face_of[g] = found;
          stack.push_back(g);
        }
      }
    }
  }
}

// Boundary edges between different faces, and solid angles seen from the centre of mass.
void OutlineFaces(const ConvexHull& hull, const Eigen::Vector3d& com, HullFaces* h) {
  const size_t n_triangles = hull.triangles.size();
  const std::vector<int>& face_of = h->face_of;
  std::vector<Face>& faces = h->faces;
  for (size_t t = 0; t < n_triangles; ++t) {
    const int me = face_of[t];
    const auto& c = hull.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const int other = face_of[h->neighbour[t][k]];
      if (other == me) continue;
      faces[me].edges[{c[k], c[(k + 1) % 3]}] = other;
    }
  }
  // Each face's plane and solid angle from its boundary polygon, walked from its lowest-ranked
  // vertex: a planar face's triangulation also depends on CGAL's order, its outline does not.
  for (size_t fi = 0; fi < faces.size(); ++fi) {
    Face& face = faces[fi];
    std::map<int, int> next;
    for (const auto& [edge, neighbour] : face.edges) next[edge.first] = edge.second;
    std::vector<Eigen::Vector3d> outline;
    int v = next.empty() ? -1 : next.begin()->first;
    for (size_t k = 0; v >= 0 && k <= next.size(); ++k) {
      outline.push_back(hull.vertices[v]);
      const auto it = next.find(v);
      v = it == next.end() ? -1 : it->second;
      if (v == next.begin()->first) break;
    }
    if (next.empty() || v != next.begin()->first || outline.size() != next.size() ||
        outline.size() < 3) {
      // Not one closed outline (degenerate): the first triangle's plane, the triangles' angles.
      for (size_t f = 0; f < n_triangles; ++f) {
        if (face_of[f] != static_cast<int>(fi)) continue;
        const auto t = Triangle(hull, f);
        face.solid_angle += SolidAngle(t[0] - com, t[1] - com, t[2] - com);
      }
      continue;
    }
    Eigen::Vector3d newell = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < outline.size(); ++i) {
      newell += outline[i].cross(outline[(i + 1) % outline.size()]);
    }
    face.normal = newell.normalized();
    face.offset = face.normal.dot(outline[0]);
    for (size_t i = 1; i + 1 < outline.size(); ++i) {
      face.solid_angle += SolidAngle(outline[0] - com, outline[i] - com, outline[i + 1] - com);
    }
  }
}

// Where the centre of mass projects onto the face's plane, and how far outside the face it lies
// (negative inside), with the edge it is furthest beyond.
double Outside(const Face& face, const std::vector<Eigen::Vector3d>& vertex,
               const Eigen::Vector3d& com, int* next) {
  const Eigen::Vector3d p = com - (face.normal.dot(com) - face.offset) * face.normal;
  double worst = -1e300;
  *next = -1;
  for (const auto& [edge, neighbour] : face.edges) {
    const Eigen::Vector3d& a = vertex[edge.first];
    const Eigen::Vector3d& b = vertex[edge.second];
    // The face lies to the left of a -> b (counter-clockwise about the outward normal).
    const Eigen::Vector3d out = (b - a).cross(face.normal).normalized();
    const double d = out.dot(p - a);
    if (d > worst) worst = d, *next = neighbour;
  }
  return worst;
}

// Each face rolls over its worst edge until the centre of mass projects inside the face it
// reached. The next face depends only on the current one, so where a face ends up is kept and
// reused by every roll that passes it (linear instead of quadratic in the number of faces).
// Returns the share of drops each face ends on.
std::vector<double> RollProbabilities(const std::vector<Face>& faces,
                                      const std::vector<Eigen::Vector3d>& vertex,
                                      const Eigen::Vector3d& com, double tolerance) {
  const auto outside = [&](int fi, int* next) { return Outside(faces[fi], vertex, com, next); };
  std::vector<int> rests_on(faces.size(), -1);
  std::vector<int> path;
  std::vector<char> on_path(faces.size(), 0);
  std::vector<double> probability(faces.size(), 0.0);
  for (size_t f = 0; f < faces.size(); ++f) {
    int current = static_cast<int>(f), next = -1;
    path.clear();
    bool cycle = false;
    for (size_t step = 0; step <= faces.size(); ++step) {
      if (rests_on[current] >= 0) {
        current = rests_on[current];
        break;
      }
      if (on_path[current]) {  // rolls round in a cycle (degenerate): bounded walk, not kept
        cycle = true;
        break;
      }
      if (outside(current, &next) <= tolerance) break;
      path.push_back(current);
      on_path[current] = 1;
      current = next;
    }
    for (int p : path) on_path[p] = 0;
    if (cycle) {
      current = static_cast<int>(f);
      for (size_t step = 0; step <= faces.size(); ++step) {
        if (outside(current, &next) <= tolerance) break;
        current = next;
      }
    } else {
      for (int p : path) rests_on[p] = current;
      rests_on[current] = current;
    }
    probability[current] += faces[f].solid_angle / (4 * M_PI);
  }
  return probability;
}

// A pose for each face some drops end on that holds the centre of mass above it (face order).
std::vector<StablePose> RestingFaces(const std::vector<Face>& faces,
                                     const std::vector<double>& probability,
                                     const std::vector<Eigen::Vector3d>& vertex,
                                     const Eigen::Vector3d& com, double tolerance) {
  std::vector<StablePose> poses;
  for (size_t f = 0; f < faces.size(); ++f) {
    if (probability[f] <= 0) continue;
    int unused;
    if (Outside(faces[f], vertex, com, &unused) > tolerance) continue;
    StablePose pose;
    pose.normal = faces[f].normal;
    pose.probability = probability[f];
    pose.height = faces[f].offset - faces[f].normal.dot(com);
    const Eigen::Matrix3d r =
        Eigen::Quaterniond::FromTwoVectors(faces[f].normal, -Eigen::Vector3d::UnitZ())
            .toRotationMatrix();
    pose.floor_from_body.linear() = r;
    pose.floor_from_body.translation() =
        Eigen::Vector3d(0, 0, faces[f].offset);  // face plane -> z = 0
    poses.push_back(pose);
  }
  return poses;
}

bool NormalLess(const StablePose& a, const StablePose& b) {
  for (int k = 0; k < 3; ++k) {
    const double x = std::round(a.normal[k] * 1e9), y = std::round(b.normal[k] * 1e9);
    if (x != y) return x < y;
  }
  return false;
}

// With the body's symmetries known, faces at one height are one pose when one of them maps
// one onto the other (a box 40 x 40 x 30 with a hole in one side rests on four sides at one
// height; two of them show the hole), or when a chain of faces joins them whose normals are
// each within 26 degrees of the next: a tessellated curve or a many-sided hull it rolls on,
// not distinct poses (a flange with 5 bolt holes on its rim: its N rim flats are one pose
// whatever N is). Rims tessellated coarser than 26 degrees are not joined.
// Splits `groups` from `first` on into those poses.
void SplitBySymmetry(const Symmetries& symmetries, size_t first,
                     std::vector<std::vector<StablePose>>* groups) {
  std::vector<std::vector<StablePose>> split;
  for (size_t g = first; g < groups->size(); ++g) {
    const std::vector<StablePose>& members = (*groups)[g];
    std::vector<size_t> root(members.size());
    for (size_t i = 0; i < root.size(); ++i) root[i] = i;
    const auto find = [&](size_t i) {
      while (root[i] != i) i = root[i] = root[root[i]];
      return i;
    };
    const double neighbours = std::cos(0.45);
    for (size_t i = 0; i < members.size(); ++i) {
      for (size_t j = i + 1; j < members.size(); ++j) {
        if (members[i].normal.dot(members[j].normal) > neighbours ||
            SameUpToSymmetry(members[i].normal, members[j].normal, symmetries)) {
          const size_t a = find(i), b = find(j);
          root[std::max(a, b)] = std::min(a, b);  // the smaller index leads: deterministic
        }
      }
    }
    std::vector<int> slot(members.size(), -1);
    for (size_t i = 0; i < members.size(); ++i) {
      const size_t r = find(i);
      if (slot[r] < 0) {
        slot[r] = static_cast<int>(split.size());
        split.emplace_back();
      }
      split[slot[r]].push_back(members[i]);
    }
  }
  groups->resize(first);
  for (std::vector<StablePose>& g : split) groups->push_back(std::move(g));
}

// Appends the poses of one resting height (`level`) to `groups`: faces by probability, a new
// pose wherever the share of drops differs by more than 0.1%, then split by the symmetries.
void GroupLevel(std::vector<StablePose> level, const Symmetries* symmetries,
                std::vector<std::vector<StablePose>>* groups) {
  std::sort(level.begin(), level.end(), [&](const StablePose& a, const StablePose& b) {
    return a.probability != b.probability ? a.probability < b.probability : NormalLess(a, b);
  });
  const size_t first = groups->size();
  for (size_t i = 0; i < level.size(); ++i) {
    if (i == 0 ||
        level[i].probability - groups->back().front().probability > 1e-3 * level[i].probability) {
      groups->emplace_back();
    }
    groups->back().push_back(level[i]);
  }
  if (symmetries != nullptr && !symmetries->empty()) SplitBySymmetry(*symmetries, first, groups);
}

// Poses by summed probability (ties keep the lower pose first), faces within a pose by normal;
// each face told its pose's index and summed probability.
std::vector<StablePose> RankPoses(std::vector<std::vector<StablePose>> groups) {
  std::vector<double> total(groups.size(), 0.0);
  for (size_t g = 0; g < groups.size(); ++g) {
    for (const StablePose& p : groups[g]) total[g] += p.probability;
    std::sort(groups[g].begin(), groups[g].end(), NormalLess);
  }
  std::vector<size_t> order(groups.size());
  for (size_t g = 0; g < order.size(); ++g) order[g] = g;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return std::round(total[a] * 1e9) >
           std::round(total[b] * 1e9);  // ties keep the lower pose first
  });
  std::vector<StablePose> sorted;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    for (StablePose p : groups[order[rank]]) {
      p.pose_probability = total[order[rank]];
      p.pose = static_cast<int>(rank);
      sorted.push_back(p);
    }
  }
  return sorted;
}

// Canonical order. Faces that are one pose up to the body's symmetry rest it at the same height
// (within 0.2% of its size: more than a facet's sagitta, far less than distinct poses differ)
// and catch the same share of drops (within 0.1%; a cylinder's flats agree to 1e-6); a
// cylinder as tall as wide rests as high on its cap as on its side, so height alone is not
// enough. Poses by summed probability, then height; faces within a pose by normal.
std::vector<StablePose> CanonicalOrder(std::vector<StablePose> poses, double size,
                                       const Symmetries* symmetries) {
  const double same_height = 2e-3 * size;
  std::sort(poses.begin(), poses.end(), [&](const StablePose& a, const StablePose& b) {
    return a.height != b.height ? a.height < b.height : NormalLess(a, b);
  });
  std::vector<std::vector<StablePose>> groups;
  for (size_t start = 0; start < poses.size();) {
    size_t end = start + 1;
    while (end < poses.size() && poses[end].height - poses[start].height <= same_height) ++end;
    GroupLevel(std::vector<StablePose>(poses.begin() + start, poses.begin() + end), symmetries,
               &groups);
    start = end;
  }
  return RankPoses(std::move(groups));
}

}  // namespace

std::vector<StablePose> StablePoses(const ConvexHull& hull, const Eigen::Vector3d& com,
                                    const Symmetries* symmetries) {
  // A sheet whose float vertices leave its plane by rounding has a hull of no real thickness.
  if (std::vector<StablePose> flat = FlatPoses(hull.vertices, com); !flat.empty()) return flat;
  if (hull.triangles.size() < 4)
    throw Error("stable poses: the points are flat (no volume to rest)");

  // Size of the body, for tolerances.
  Eigen::AlignedBox3d box;
  for (const auto& p : hull.vertices) box.extend(p);
  const double size = box.diagonal().norm();

  HullFaces h;
  h.neighbour = Neighbours(hull);
  GroupFaces(hull, size, &h);
  OutlineFaces(hull, com, &h);
  const double tolerance = 1e-9 * size;
  const std::vector<double> probability = RollProbabilities(h.faces, hull.vertices, com, tolerance);
  return CanonicalOrder(RestingFaces(h.faces, probability, hull.vertices, com, tolerance), size,
                        symmetries);
}

std::vector<StablePose> StablePoses(const std::vector<Part>& parts,
                                    const std::vector<Instance>& instances) {
  std::vector<Eigen::Vector3d> points;
  std::optional<ConvexHull> moved;  // one instance with its hull: the hull moved, not recomputed
  if (instances.size() == 1 && parts.at(instances[0].part).hull) {
    try {
      moved = TransformedHull(*parts.at(instances[0].part).hull, instances[0].world_from_model);
    } catch (const Error&) {  // a mirroring placement: the hull of the moved points below
    }
  }
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  double weight = 0;
  for (const Instance& i : instances) {
    const Part& part = parts.at(i.part);
    // The hull of the hulls' corners is the hull of every vertex, for far fewer points.
    if (moved) {
      // The hull above holds every corner.
    } else if (part.hull) {
      for (const Eigen::Vector3d& p : part.hull->vertices) points.push_back(i.world_from_model * p);
    } else {
      for (const Eigen::Vector3f& p : part.mesh.positions)
        points.push_back(i.world_from_model * p.cast<double>());
    }
    if (part.mass.volume_mm3 > 0) {
      moment += part.mass.volume_mm3 * (i.world_from_model * part.mass.center_of_mass);
      weight += part.mass.volume_mm3;
    } else {  // open mesh: its box centre, weighted by area as a thin shell
      const double area = part.mesh.SurfaceArea();
      moment += area * (i.world_from_model * part.mesh.Bounds().center());
      weight += area;
    }
  }
  if (weight <= 0) {
    throw Error("stable poses: '" +
                (instances.empty() ? std::string() : parts[instances[0].part].name) +
                "' has no volume or area");
  }
  // One placed part: its symmetries, turned into the body frame, decide which faces are one pose.
  std::optional<Symmetries> turned;
  if (instances.size() == 1 && !parts.at(instances[0].part).symmetries.empty())
    turned =
        parts.at(instances[0].part).symmetries.InFrame(instances[0].world_from_model.inverse());
  const Symmetries* symmetries = turned ? &*turned : nullptr;
  if (moved) return StablePoses(*moved, moment / weight, symmetries);
  return StablePoses(points, moment / weight, symmetries);
}

}  // namespace cadsynth
