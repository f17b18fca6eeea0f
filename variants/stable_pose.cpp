#include "variants/stable_pose.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/convex_hull_3.h>

#include "cad/error.h"

namespace cadsynth {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using HullMesh = CGAL::Surface_mesh<Point>;

Eigen::Vector3d ToEigen(const Point& p) { return {p.x(), p.y(), p.z()}; }

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

std::vector<StablePose> StablePoses(const std::vector<Eigen::Vector3d>& points,
                                    const Eigen::Vector3d& com) {
  if (points.size() < 4) throw Error("stable poses: need at least 4 points");
  // Meshes repeat a vertex once per smoothing group (per flat face on faceted parts): hull each
  // position once.
  std::vector<Eigen::Vector3d> unique = points;
  const auto less = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::sort(unique.begin(), unique.end(), less);
  unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
  std::vector<Point> input;
  input.reserve(unique.size());
  for (const auto& p : unique) input.emplace_back(p.x(), p.y(), p.z());
  HullMesh hull;
  CGAL::convex_hull_3(input.begin(), input.end(), hull);
  if (hull.number_of_faces() < 4)
    throw Error("stable poses: the points are flat (no volume to rest)");

  // Size of the body, for tolerances.
  Eigen::AlignedBox3d box;
  for (const auto& p : points) box.extend(p);
  const double size = box.diagonal().norm();

  // Group hull triangles into planar faces.
  std::vector<int> face_of(hull.number_of_faces() + hull.number_of_removed_faces(), -1);
  std::vector<Face> faces;
  // CGAL lists the hull's vertices and triangles in an order that depends on memory addresses, so
  // two calls on the same points could group faces from other first triangles and differ in the
  // last bits. Everything below works in an order of the geometry alone: vertices by coordinates
  // (their rank is their id) and triangles by their vertices' ranks, starting at the lowest.
  std::vector<HullMesh::Vertex_index> by_position(hull.vertices().begin(), hull.vertices().end());
  std::sort(by_position.begin(), by_position.end(),
            [&](HullMesh::Vertex_index a, HullMesh::Vertex_index b) {
              return less(ToEigen(hull.point(a)), ToEigen(hull.point(b)));
            });
  std::vector<int> rank(hull.number_of_vertices() + hull.number_of_removed_vertices(), -1);
  for (size_t r = 0; r < by_position.size(); ++r) rank[by_position[r].idx()] = static_cast<int>(r);
  const auto corners = [&](HullMesh::Face_index f) {
    std::array<int, 3> c;
    int k = 0;
    for (auto v : CGAL::vertices_around_face(hull.halfedge(f), hull)) c[k++] = rank[v.idx()];
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());  // keeps the winding
    return c;
  };
  std::vector<HullMesh::Face_index> handles(hull.faces().begin(), hull.faces().end());
  std::sort(handles.begin(), handles.end(), [&](HullMesh::Face_index a, HullMesh::Face_index b) {
    return corners(a) < corners(b);
  });
  const auto triangle = [&](HullMesh::Face_index f) {
    std::array<Eigen::Vector3d, 3> t;
    const std::array<int, 3> c = corners(f);
    for (int k = 0; k < 3; ++k) t[k] = ToEigen(hull.point(by_position[c[k]]));
    return t;
  };
  // A face is grown from its first triangle (in that order) over neighbouring triangles in
  // that triangle's plane: a convex polytope's facet is connected, so this finds the triangles a
  // search of every face would, in time linear in the hull's size.
  std::vector<Eigen::Vector3d> normal_of(face_of.size());
  for (auto f : handles) {
    const auto t = triangle(f);
    normal_of[f.idx()] = (t[1] - t[0]).cross(t[2] - t[0]).normalized();
  }
  std::vector<HullMesh::Face_index> stack;
  for (auto seed : handles) {
    if (face_of[seed.idx()] >= 0) continue;
    const int found = static_cast<int>(faces.size());
    const Eigen::Vector3d n = normal_of[seed.idx()];
    faces.push_back(Face{n, n.dot(triangle(seed)[0]), {}, 0});
    face_of[seed.idx()] = found;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const HullMesh::Face_index f = stack.back();
      stack.pop_back();
      for (auto h : CGAL::halfedges_around_face(hull.halfedge(f), hull)) {
        const HullMesh::Face_index g = hull.face(hull.opposite(h));
        if (face_of[g.idx()] >= 0) continue;
        const auto t = triangle(g);
        if (faces[found].normal.dot(normal_of[g.idx()]) > 1 - 1e-9 &&
            std::abs(normal_of[g.idx()].dot(t[0]) - faces[found].offset) < 1e-7 * size) {
          face_of[g.idx()] = found;
          stack.push_back(g);
        }
      }
    }
  }
  // Boundary edges between different faces, and solid angles seen from the centre of mass.
  for (auto f : handles) {
    const int me = face_of[f.idx()];
    for (auto h : CGAL::halfedges_around_face(hull.halfedge(f), hull)) {
      const int other = face_of[hull.face(hull.opposite(h)).idx()];
      if (other == me) continue;
      faces[me].edges[{rank[hull.source(h).idx()], rank[hull.target(h).idx()]}] = other;
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
      outline.push_back(ToEigen(hull.point(by_position[v])));
      const auto it = next.find(v);
      v = it == next.end() ? -1 : it->second;
      if (v == next.begin()->first) break;
    }
    if (next.empty() || v != next.begin()->first || outline.size() != next.size() ||
        outline.size() < 3) {
      // Not one closed outline (degenerate): the first triangle's plane, the triangles' angles.
      for (auto f : handles) {
        if (face_of[f.idx()] != static_cast<int>(fi)) continue;
        const auto t = triangle(f);
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

  // Where the centre of mass projects onto each face's plane, and how far outside the face it lies
  // (negative inside), with the edge it is furthest beyond.
  const auto outside = [&](int fi, int* next) {
    const Face& face = faces[fi];
    const Eigen::Vector3d p = com - (face.normal.dot(com) - face.offset) * face.normal;
    double worst = -1e300;
    *next = -1;
    for (const auto& [edge, neighbour] : face.edges) {
      const Eigen::Vector3d a = ToEigen(hull.point(by_position[edge.first]));
      const Eigen::Vector3d b = ToEigen(hull.point(by_position[edge.second]));
      // The face lies to the left of a -> b (counter-clockwise about the outward normal).
      const Eigen::Vector3d out = (b - a).cross(face.normal).normalized();
      const double d = out.dot(p - a);
      if (d > worst) worst = d, *next = neighbour;
    }
    return worst;
  };
  const double tolerance = 1e-9 * size;
  // Each face rolls over its worst edge until the centre of mass projects inside the face it
  // reached. The next face depends only on the current one, so where a face ends up is kept and
  // reused by every roll that passes it (linear instead of quadratic in the number of faces).
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

  std::vector<StablePose> poses;
  for (size_t f = 0; f < faces.size(); ++f) {
    if (probability[f] <= 0) continue;
    int unused;
    if (outside(static_cast<int>(f), &unused) > tolerance) continue;
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
  // Canonical order. Faces that are one pose up to the body's symmetry rest it at the same height
  // (within 0.2% of its size: more than a facet's sagitta, far less than distinct poses differ)
  // and catch the same share of drops (within 0.1%; a cylinder's flats agree to 1e-6); a
  // cylinder as tall as wide rests as high on its cap as on its side, so height alone is not
  // enough. Poses by summed probability, then height; faces within a pose by normal.
  const double same_height = 2e-3 * size;
  const auto normal_less = [](const StablePose& a, const StablePose& b) {
    for (int k = 0; k < 3; ++k) {
      const double x = std::round(a.normal[k] * 1e9), y = std::round(b.normal[k] * 1e9);
      if (x != y) return x < y;
    }
    return false;
  };
  std::sort(poses.begin(), poses.end(), [&](const StablePose& a, const StablePose& b) {
    return a.height != b.height ? a.height < b.height : normal_less(a, b);
  });
  std::vector<std::vector<StablePose>> groups;
  for (size_t start = 0; start < poses.size();) {
    size_t end = start + 1;
    while (end < poses.size() && poses[end].height - poses[start].height <= same_height) ++end;
    std::vector<StablePose> level(poses.begin() + start, poses.begin() + end);
    std::sort(level.begin(), level.end(), [&](const StablePose& a, const StablePose& b) {
      return a.probability != b.probability ? a.probability < b.probability : normal_less(a, b);
    });
    for (size_t i = 0; i < level.size(); ++i) {
      if (i == 0 ||
          level[i].probability - groups.back().front().probability > 1e-3 * level[i].probability) {
        groups.emplace_back();
      }
      groups.back().push_back(level[i]);
    }
    start = end;
  }
  std::vector<double> total(groups.size(), 0.0);
  for (size_t g = 0; g < groups.size(); ++g) {
    for (const StablePose& p : groups[g]) total[g] += p.probability;
    std::sort(groups[g].begin(), groups[g].end(), normal_less);
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

std::vector<StablePose> StablePoses(const std::vector<Part>& parts,
                                    const std::vector<Instance>& instances) {
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  double weight = 0;
  for (const Instance& i : instances) {
    const Part& part = parts.at(i.part);
    for (const Eigen::Vector3f& p : part.mesh.positions)
      points.push_back(i.world_from_model * p.cast<double>());
    if (part.mass.volume_mm3 > 0) {
      moment += part.mass.volume_mm3 * (i.world_from_model * part.mass.center_of_mass);
      weight += part.mass.volume_mm3;
    } else {  // open mesh: its box centre, weighted by area as a thin shell
      const double area = part.mesh.SurfaceArea();
      moment += area * (i.world_from_model * part.mesh.Bounds().center());
      weight += area;
    }
  }
  if (weight <= 0) throw Error("stable poses: the body has no volume or area");
  return StablePoses(points, moment / weight);
}

}  // namespace cadsynth
