#include "tools/pipeline/inspect.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "cad/gear_recognition.h"
#include "cad/symmetry.h"

namespace cadsynth {
namespace {

std::string Hex(const std::optional<Eigen::Vector3f>& color) {
  if (!color) return "-";
  char buffer[16];
  const auto byte = [](float v) {
    return static_cast<int>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255));
  };
  std::snprintf(buffer, sizeof(buffer), "#%02x%02x%02x", byte(color->x()), byte(color->y()),
                byte(color->z()));
  return buffer;
}

// Names may hold line breaks and tabs (STEP allows them): keep the table on one line per row.
std::string Printable(const std::string& name) {
  std::string out;
  for (char c : name) out += (static_cast<unsigned char>(c) < 0x20) ? ' ' : c;
  return out;
}

std::vector<int> InstanceCounts(const Assembly& a) {
  std::vector<int> counts(a.parts.size(), 0);
  for (const Instance& i : a.instances) ++counts[i.part];
  return counts;
}

// What the pipeline works out about each part (issue 20): its symmetries, found on its mesh as
// a run finds them, and the gear it is, if it is one.
struct Understood {
  std::string error;  // why nothing was looked for
  DetectedSymmetries symmetries;
  std::optional<RecognizedGear> gear;
};

std::vector<Understood> Understand(const Assembly& a) {
  std::vector<Understood> out(a.parts.size());
  tbb::parallel_for(size_t{0}, a.parts.size(), [&](size_t i) {
    const Part& p = a.parts[i];
    if (p.mesh.triangles.empty()) {
      out[i].error = "no triangles";
      return;
    }
    try {
      out[i].symmetries = DetectSymmetries(p.mesh, PartSymmetryOptions(p));
      CompareBrepFaces(p, &out[i].symmetries);
      out[i].gear = RecognizePartGear(p, out[i].symmetries);
    } catch (const Error& e) {
      out[i].error = e.what();
    }
  });
  return out;
}

}  // namespace

namespace {

Assembly Read(const std::filesystem::path& path, ImportOptions options,
              const ReaderProcess* reader) {
  options.tessellation.measure_deviation = true;
  std::vector<std::string> warnings;
  Assembly assembly = ImportGuarded(path, options, reader, &warnings);
  for (const std::string& warning : warnings) Warn(warning);
  return assembly;
}

// The B-rep's surface-to-surface check: null without a B-rep; else whether every surface found a
// partner under every symmetry, and the largest distance between a moved surface and its partner.
nlohmann::ordered_json BrepFacesJson(const DetectedSymmetries& d) {
  if (d.discrete_brep_mm.empty() && d.continuous_brep_mm.empty()) return nullptr;
  double worst = 0;
  for (double v : d.discrete_brep_mm) worst = std::max(worst, v);
  for (double v : d.continuous_brep_mm) worst = std::max(worst, v);
  nlohmann::ordered_json j = {{"all_match", std::isfinite(worst)}};
  j["largest_distance_mm"] = std::isfinite(worst) ? nlohmann::ordered_json(worst) : nullptr;
  j["free_form_face_images_not_compared"] = d.brep_faces_not_compared;
  return j;
}

}  // namespace

std::string InspectText(const std::filesystem::path& path, const ImportOptions& options,
                        const ReaderProcess* reader) {
  const Assembly a = Read(path, options, reader);
  const std::vector<int> counts = InstanceCounts(a);
  std::ostringstream out;
  out << path.string() << "\n  format " << a.format << ", unit "
      << (a.length_unit.empty() ? "?" : a.length_unit) << ", '" << a.name << "': " << a.parts.size()
      << " parts, " << a.instances.size() << " instances (sizes in mm)\n\n";
  char line[512];
  std::snprintf(line, sizeof(line), "  %3s  %-28s %5s  %-28s %9s  %-7s  %13s  %-6s  %s\n", "id",
                "part", "inst", "size x y z", "triangles", "colour", "volume mm3", "closed",
                "deviation mm");
  out << line;
  for (size_t i = 0; i < a.parts.size(); ++i) {
    const Part& p = a.parts[i];
    const Eigen::Vector3d s = p.mesh.Bounds().sizes();
    char size[64];
    std::snprintf(size, sizeof(size), "%.4g x %.4g x %.4g", s.x(), s.y(), s.z());
    char volume[32] = "-";
    if (p.mass.volume_mm3 > 0) std::snprintf(volume, sizeof(volume), "%.6g", p.mass.volume_mm3);
    char deviation[32] = "-";
    if (p.max_deviation_mm >= 0)
      std::snprintf(deviation, sizeof(deviation), "%.3g", p.max_deviation_mm);
    std::snprintf(line, sizeof(line), "  %3zu  %-28.28s %5d  %-28s %9zu  %-7s  %13s  %-6s  %s\n",
                  i + 1, Printable(p.name).c_str(), counts[i], size, p.mesh.num_triangles(),
                  Hex(p.color).c_str(), volume, p.watertight ? "yes" : "NO", deviation);
    out << line;
  }
  // Symmetries found on each part's mesh (cad/symmetry.h), as the pipeline finds them, and the
  // gears recognised (cad/gear_recognition.h).
  const std::vector<Understood> understood = Understand(a);
  out << "\n  symmetries (found on the meshes, in each part's model frame):\n";
  for (size_t i = 0; i < a.parts.size(); ++i) {
    const Understood& u = understood[i];
    const std::string text =
        !u.error.empty() ? "not looked for: " + u.error : DescribeSymmetries(u.symmetries);
    std::snprintf(line, sizeof(line), "  %3zu  %-28.28s %s\n", i + 1,
                  Printable(a.parts[i].name).c_str(), text.c_str());
    out << line;
  }
  bool any_gear = false;
  for (size_t i = 0; i < a.parts.size(); ++i) {
    if (!understood[i].gear) continue;
    if (!any_gear) out << "\n  gears (recognised on the meshes):\n";
    any_gear = true;
    std::snprintf(line, sizeof(line), "  %3zu  %-28.28s %s\n", i + 1,
                  Printable(a.parts[i].name).c_str(), DescribeGear(*understood[i].gear).c_str());
    out << line;
  }
  out << "\n  assembly tree (instance: part id, position of its model frame in the root frame, "
         "mm):\n";
  // Print each instance under its path, opening the sub-assemblies it is in as they appear.
  std::vector<std::string> open;
  for (const Instance& i : a.instances) {
    std::vector<std::string> levels;
    std::string path = i.path.empty() ? i.name : i.path;
    for (size_t start = 0, slash; start <= path.size(); start = slash + 1) {
      slash = path.find('/', start);
      if (slash == std::string::npos) slash = path.size();
      levels.push_back(path.substr(start, slash - start));
    }
    size_t common = 0;
    while (common < open.size() && common + 1 < levels.size() && open[common] == levels[common])
      ++common;
    open.resize(common);
    for (size_t d = common; d + 1 < levels.size(); ++d) {
      out << "    " << std::string(2 * d, ' ') << Printable(levels[d]) << "\n";
      open.push_back(levels[d]);
    }
    const Eigen::Vector3d t = i.world_from_model.translation();
    std::snprintf(line, sizeof(line), "%s: part %d at (%.4g, %.4g, %.4g)%s%s\n",
                  Printable(levels.back()).c_str(), i.part + 1, t.x(), t.y(), t.z(),
                  i.color ? ", colour " : "", i.color ? Hex(i.color).c_str() : "");
    out << "    " << std::string(2 * (levels.size() - 1), ' ') << line;
  }
  return out.str();
}

std::string InspectJson(const std::filesystem::path& path, const ImportOptions& options,
                        const ReaderProcess* reader) {
  using Json = nlohmann::ordered_json;
  const Assembly a = Read(path, options, reader);
  const std::vector<int> counts = InstanceCounts(a);
  const auto vec = [](const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); };
  const std::vector<Understood> understood = Understand(a);
  Json parts = Json::array();
  for (size_t i = 0; i < a.parts.size(); ++i) {
    const Part& p = a.parts[i];
    const Understood& u = understood[i];
    Json symmetry;
    if (u.error.empty()) {
      Json axes = Json::array();
      for (const DetectedSymmetries::Axis& axis : u.symmetries.axes)
        axes.push_back({{"direction", vec(axis.direction)}, {"order", axis.order}});
      double worst = 0;
      for (double d : u.symmetries.discrete_deviation_mm) worst = std::max(worst, d);
      for (double d : u.symmetries.continuous_deviation_mm) worst = std::max(worst, d);
      symmetry = {{"description", DescribeSymmetries(u.symmetries)},
                  {"discrete", u.symmetries.symmetries.discrete.size()},
                  {"continuous", u.symmetries.symmetries.continuous.size()},
                  {"axes", axes},
                  {"centre_mm", vec(u.symmetries.centre)},
                  {"largest_deviation_mm", worst},
                  {"brep_faces", BrepFacesJson(u.symmetries)},
                  {"tolerance_mm", u.symmetries.tolerance_mm}};
    }
    Json gear;
    if (u.gear) {
      const RecognizedGear& g = *u.gear;
      const double deg = 180 / M_PI;
      gear = {{"teeth", g.teeth},
              {"internal", g.internal},
              {"module_mm", g.module_mm},
              {"transverse_module_mm", g.transverse_module_mm},
              {"pressure_angle_deg", g.pressure_angle_rad * deg},
              {"helix_angle_deg", g.helix_angle_rad * deg},
              {"herringbone", g.herringbone},
              {"profile_shift", g.profile_shift},
              {"face_width_mm", g.face_width_mm},
              {"bore_diameter_mm", g.bore_diameter_mm},
              {"tip_radius_mm", g.tip_radius_mm},
              {"root_radius_mm", g.root_radius_mm},
              {"base_radius_mm", g.base_radius_mm},
              {"involute_deviation_mm", g.involute_deviation_mm},
              {"axis", vec(g.axis)},
              {"centre_mm", vec(g.centre)}};
    }
    const Eigen::AlignedBox3d box = p.mesh.Bounds();
    Json part = {
        {"id", i + 1},
        {"name", p.name},
        {"instances", counts[i]},
        {"bbox_min_mm", vec(box.min())},
        {"bbox_max_mm", vec(box.max())},
        {"size_mm", vec(box.sizes())},
        {"triangles", p.mesh.num_triangles()},
        {"color", p.color ? Json(Hex(p.color)) : Json()},
        {"volume_mm3", p.mass.volume_mm3 > 0 ? Json(p.mass.volume_mm3) : Json()},
        {"volume_from", p.mass_from_brep ? "brep" : (p.mass.volume_mm3 > 0 ? "mesh" : "none")},
        {"watertight", p.watertight},
        {"max_deviation_mm", p.max_deviation_mm >= 0 ? Json(p.max_deviation_mm) : Json()},
        {"symmetry", symmetry},
        {"symmetry_error", u.error.empty() ? Json() : Json(u.error)},
        {"gear", gear}};
    parts.push_back(part);
  }
  Json instances = Json::array();
  for (const Instance& i : a.instances) {
    Json pose = Json::array();
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) pose.push_back(i.world_from_model.matrix()(r, c));
    }
    instances.push_back({{"name", i.name},
                         {"path", i.path},
                         {"part", i.part + 1},
                         {"root_from_model", pose},
                         {"color", i.color ? Json(Hex(i.color)) : Json()}});
  }
  const Json out = {{"file", path.string()}, {"format", a.format}, {"length_unit", a.length_unit},
                    {"name", a.name},        {"parts", parts},     {"instances", instances}};
  return out.dump(2) + "\n";
}

}  // namespace cadsynth
