#include "dataset/point_cloud.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "cad/core/error.h"
#include "cad/core/random.h"
#include "cad/core/util.h"

namespace cadsynth {

std::vector<Eigen::Vector3f> SampleSurface(const Mesh& mesh, int count, uint64_t seed) {
  if (mesh.empty()) throw Error("point sampling: empty mesh");
  if (count < 1) throw Error("point sampling: count must be positive");
  std::vector<double> cumulative;
  cumulative.reserve(mesh.num_triangles());
  double total = 0;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    total += 0.5 * (mesh.positions[t[1]].cast<double>() - a)
                       .cross(mesh.positions[t[2]].cast<double>() - a)
                       .norm();
    cumulative.push_back(total);
  }
  std::vector<Eigen::Vector3f> points;
  points.reserve(count);
  for (int i = 0; i < count; ++i) {
    const double pick = UniformDraw(seed, streams::kPointTriangle, i) * total;
    const size_t t =
        std::min(static_cast<size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                     cumulative.begin()),
                 cumulative.size() - 1);
    double r1 = UniformDraw(seed, streams::kPointU, i), r2 = UniformDraw(seed, streams::kPointV, i);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;  // fold into the triangle: uniform by area
    const auto& tri = mesh.triangles[t];
    const Eigen::Vector3f a = mesh.positions[tri[0]], b = mesh.positions[tri[1]],
                          c = mesh.positions[tri[2]];
    points.push_back(a + float(r1) * (b - a) + float(r2) * (c - a));
  }
  return points;
}

std::vector<int> FarthestPoints(const std::vector<Eigen::Vector3f>& points, int k) {
  std::vector<int> chosen;
  if (points.empty() || k < 1) return chosen;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (const auto& p : points) centroid += p / float(points.size());
  std::vector<float> nearest(points.size(), std::numeric_limits<float>::infinity());
  int next = 0;
  for (size_t i = 1; i < points.size(); ++i) {
    if ((points[i] - centroid).squaredNorm() > (points[next] - centroid).squaredNorm())
      next = static_cast<int>(i);
  }
  while (static_cast<int>(chosen.size()) < std::min<int>(k, static_cast<int>(points.size()))) {
    chosen.push_back(next);
    int farthest = 0;
    float best = -1;
    for (size_t i = 0; i < points.size(); ++i) {
      nearest[i] = std::min(nearest[i], (points[i] - points[next]).squaredNorm());
      if (nearest[i] > best) best = nearest[i], farthest = static_cast<int>(i);
    }
    next = farthest;
  }
  return chosen;
}

std::vector<Eigen::Vector3f> SampleEvenly(const Mesh& mesh, int count, uint64_t seed) {
  const std::vector<Eigen::Vector3f> candidates = SampleSurface(mesh, 10 * count, seed);
  std::vector<Eigen::Vector3f> points;
  for (int i : FarthestPoints(candidates, count)) points.push_back(candidates[i]);
  return points;
}

Keypoints ComputeKeypoints(const Mesh& mesh, const std::vector<Eigen::Vector3f>& surface_points) {
  Keypoints k;
  for (int i : FarthestPoints(surface_points, 8)) k.fps8.push_back(surface_points[i]);
  for (int i : FarthestPoints(surface_points, 16)) k.fps16.push_back(surface_points[i]);
  const Eigen::AlignedBox3d box = mesh.Bounds();
  k.center = box.center().cast<float>();
  for (int c = 0; c < 8; ++c)
    k.corners[c] = box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)).cast<float>();
  return k;
}

std::string EncodePointPly(const std::vector<Eigen::Vector3f>& points) {
  std::ostringstream out;
  out << "ply\nformat ascii 1.0\ncomment cadsynth model points, units: mm\nelement vertex "
      << points.size() << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  out.precision(7);
  for (const auto& p : points) out << p.x() << " " << p.y() << " " << p.z() << "\n";
  return out.str();
}

std::vector<Eigen::Vector3f> DecodePointPly(const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  std::string line;
  long count = -1;
  bool ascii = false, header_done = false;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.rfind("format ", 0) == 0) ascii = line.rfind("format ascii", 0) == 0;
    if (line.rfind("element vertex ", 0) == 0) {
      // A count that is not a number, or more than the text could hold, is refused below.
      const char* first = line.c_str() + 15;
      const char* last = line.c_str() + line.size() - (line.back() == '\r' ? 1 : 0);
      long value = -1;
      const auto [end, ec] = std::from_chars(first, last, value);
      count = ec == std::errc() && end == last ? value : -1;
    }
    if (line == "end_header" || line == "end_header\r") {
      header_done = true;
      break;
    }
  }
  if (!header_done || !ascii || count < 0) {
    throw Error(
        origin +
        ": not an ASCII point PLY (needs 'format ascii', 'element vertex N' and 'end_header')");
  }
  // Each point takes at least 6 characters ("0 0 0\n"): a count above that is a damaged header.
  if (static_cast<size_t>(count) > text.size() / 6 + 1) {
    throw Error(origin + ": the header's " + std::to_string(count) +
                " points cannot fit in a file of " + std::to_string(text.size()) + " bytes");
  }
  std::vector<Eigen::Vector3f> points;
  points.reserve(static_cast<size_t>(count));
  for (long i = 0; i < count; ++i) {
    ++line_no;
    Eigen::Vector3f p;
    if (!std::getline(in, line) || !(std::istringstream(line) >> p.x() >> p.y() >> p.z())) {
      throw Error(origin + ":" + std::to_string(line_no) + ": expected vertex " +
                  std::to_string(i + 1) + " of " + std::to_string(count) + " as 'x y z'");
    }
    points.push_back(p);
  }
  return points;
}

}  // namespace cadsynth
