#include "dataset/bop_read.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/file_io.h"

namespace cadsynth {

namespace {

// The reason in nlohmann's wording "[json.exception.x.n] ...: REASON; last read: ...".
std::string Reason(const std::string& what) {
  std::string reason = what;
  const size_t dash = reason.rfind(" - ");
  if (dash != std::string::npos) reason = reason.substr(dash + 3);
  const size_t bracket = reason.find("] ");
  if (reason.rfind("[json.exception", 0) == 0 && bracket != std::string::npos)
    reason = reason.substr(bracket + 2);
  const size_t last = reason.find("; last read");
  if (last != std::string::npos) reason = reason.substr(0, last);
  if (reason.size() > 200) reason = reason.substr(0, 200) + "...";
  return reason;
}

nlohmann::json Parse(const std::string& text, const std::string& origin) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw Error(JsonErrorMessage(origin, text, e));
  }
}

double Number(const nlohmann::json& value, const std::string& where) {
  if (!value.is_number())
    throw Error(where + ": expected a number, got " + value.dump().substr(0, 40));
  const double v = value.get<double>();
  if (!std::isfinite(v)) throw Error(where + ": not a finite number");
  return v;
}

// A pose from BOP's R (9 numbers, row-major) and t (3 numbers); R must be a rotation.
Eigen::Isometry3d Pose(const std::vector<double>& r, const std::vector<double>& t,
                       const std::string& where) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 9; ++i) pose.linear()(i / 3, i % 3) = r[i];
  for (int i = 0; i < 3; ++i) pose.translation()(i) = t[i];
  const double det = pose.linear().determinant();
  if (!(std::abs(det - 1.0) <= 1e-3)) {
    std::ostringstream text;
    text << where << ": R is not a rotation (determinant " << det << ")";
    throw Error(text.str());
  }
  return pose;
}

std::vector<double> Numbers(const nlohmann::json& value, size_t n, const std::string& where) {
  if (!value.is_array() || value.size() != n)
    throw Error(where + ": expected " + std::to_string(n) + " numbers");
  std::vector<double> out;
  for (const nlohmann::json& v : value) out.push_back(Number(v, where));
  return out;
}

const nlohmann::json& Member(const nlohmann::json& object, const char* key,
                             const std::string& where) {
  if (!object.is_object()) throw Error(where + ": expected an object");
  const auto found = object.find(key);
  if (found == object.end()) throw Error(where + ": no '" + key + "'");
  return *found;
}

}  // namespace

std::string JsonErrorMessage(const std::string& origin, const std::string& text,
                             const std::exception& error) {
  if (const auto* parse = dynamic_cast<const nlohmann::json::parse_error*>(&error)) {
    // Its byte is 1-based, the one after the last read.
    const size_t byte = std::min(parse->byte > 0 ? parse->byte - 1 : 0, text.size());
    size_t line = 1, column = 1;
    for (size_t i = 0; i < byte; ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    return origin + ":" + std::to_string(line) + ":" + std::to_string(column) +
           ": not valid JSON (" + Reason(error.what()) + ")";
  }
  return origin + ": " + Reason(error.what());
}

std::optional<int> ParseBopId(std::string_view text) {
  int value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || text.empty() || value < 0)
    return std::nullopt;
  return value;
}

std::vector<BopEstimate> ParseBopResults(const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  std::vector<BopEstimate> out;
  std::string line;
  for (int line_no = 1; std::getline(in, line); ++line_no) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || (line_no == 1 && line.rfind("scene_id", 0) == 0)) continue;
    const std::string where = origin + ":" + std::to_string(line_no);
    std::vector<std::string> fields;
    std::stringstream split(line);
    for (std::string f; std::getline(split, f, ',');) fields.push_back(f);
    if (fields.size() < 6 || fields.size() > 7) {
      throw Error(where + ": expected scene_id,im_id,obj_id,score,R,t[,time], got " +
                  std::to_string(fields.size()) + " fields");
    }
    const auto numbers = [&](const std::string& field, size_t n, const char* what) {
      std::istringstream s(field);
      std::vector<double> v;
      for (double x; v.size() <= n && s >> x;) v.push_back(x);
      if (v.size() != n || !(s >> std::ws).eof()) {
        throw Error(where + ": " + what + " needs " + std::to_string(n) +
                    " space-separated numbers, got '" + field.substr(0, 80) +
                    (field.size() > 80 ? "...'" : "'"));
      }
      for (double x : v) {
        if (!std::isfinite(x)) throw Error(where + ": " + what + " is not a finite number");
      }
      return v;
    };
    BopEstimate e;
    int* ids[3] = {&e.scene_id, &e.im_id, &e.obj_id};
    for (int i = 0; i < 3; ++i) {
      std::string field = fields[i];
      field.erase(0, field.find_first_not_of(" \t"));
      field.erase(field.find_last_not_of(" \t") + 1);
      const auto id = ParseBopId(field);
      if (!id) {
        throw Error(where + ": scene_id, im_id and obj_id must be whole numbers, got '" +
                    fields[i].substr(0, 40) + "'");
      }
      *ids[i] = *id;
    }
    e.score = numbers(fields[3], 1, "score")[0];
    e.cam_from_model = Pose(numbers(fields[4], 9, "R"), numbers(fields[5], 3, "t"), where);
    out.push_back(e);
  }
  return out;
}

BopSceneGt ParseSceneGt(const std::string& text, const std::string& origin) {
  const nlohmann::json gt = Parse(text, origin);
  if (!gt.is_object()) throw Error(origin + ": expected an object of images");
  BopSceneGt out;
  for (const auto& [key, list] : gt.items()) {
    const std::string where = origin + ": image '" + key.substr(0, 40) + "'";
    const auto im = ParseBopId(key);
    if (!im) throw Error(where + ": an image id must be a whole number");
    if (!list.is_array()) throw Error(where + ": expected a list of instances");
    out.push_back({*im, {}});
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string at = where + " instance " + std::to_string(i);
      const nlohmann::json& id = Member(list[i], "obj_id", at);
      if (!id.is_number_integer() || id.get<int64_t>() < 0 || id.get<int64_t>() > 2147483647)
        throw Error(at + ": obj_id must be a whole number");
      BopGroundTruth g;
      g.obj_id = id.get<int>();
      g.cam_from_model = Pose(Numbers(Member(list[i], "cam_R_m2c", at), 9, at + " cam_R_m2c"),
                              Numbers(Member(list[i], "cam_t_m2c", at), 3, at + " cam_t_m2c"), at);
      out.back().second.push_back(g);
    }
  }
  return out;
}

std::vector<BopModelInfo> ParseModelsInfo(const std::string& text, const std::string& origin) {
  const nlohmann::json info = Parse(text, origin);
  if (!info.is_object()) throw Error(origin + ": expected an object of models");
  std::vector<BopModelInfo> out;
  for (const auto& [key, entry] : info.items()) {
    const std::string where = origin + ": model '" + key.substr(0, 40) + "'";
    const auto id = ParseBopId(key);
    if (!id) throw Error(where + ": an object id must be a whole number");
    BopModelInfo m;
    m.obj_id = *id;
    m.diameter = Number(Member(entry, "diameter", where), where + " diameter");
    if (!(m.diameter > 0)) throw Error(where + ": the diameter must be positive");
    for (const char* key_name : {"symmetries_discrete", "symmetries_continuous"}) {
      const auto found = entry.find(key_name);
      if (found == entry.end()) continue;
      if (!found->is_array()) throw Error(where + ": " + key_name + " must be a list");
      m.symmetric = m.symmetric || !found->empty();
    }
    // The symmetries themselves, for MSSD.
    std::vector<Eigen::Isometry3d> discrete = {Eigen::Isometry3d::Identity()};
    if (const auto found = entry.find("symmetries_discrete"); found != entry.end()) {
      for (const nlohmann::json& matrix : *found) {
        const std::string at = where + " symmetries_discrete";
        if (!matrix.is_array() || matrix.size() != 16)
          throw Error(at + ": each is a 4 x 4 matrix of 16 numbers");
        Eigen::Matrix4d t;
        for (int k = 0; k < 16; ++k) t(k / 4, k % 4) = Number(matrix[k], at);
        Eigen::Isometry3d pose;
        pose.matrix() = t;
        if (!((t.topLeftCorner<3, 3>() * t.topLeftCorner<3, 3>().transpose() -
               Eigen::Matrix3d::Identity())
                      .cwiseAbs()
                      .maxCoeff() < 1e-3 &&
              t.topLeftCorner<3, 3>().determinant() > 0))
          throw Error(at + ": the upper-left 3 x 3 block must be a rotation");
        discrete.push_back(pose);
      }
    }
    std::vector<Eigen::Isometry3d> continuous;
    if (const auto found = entry.find("symmetries_continuous"); found != entry.end()) {
      const int steps = static_cast<int>(std::ceil(M_PI / 0.01));
      for (const nlohmann::json& sym : *found) {
        const std::string at = where + " symmetries_continuous";
        if (!sym.is_object()) throw Error(at + ": each is {\"axis\", \"offset\"}");
        Eigen::Vector3d axis, offset;
        for (int k = 0; k < 3; ++k) {
          const nlohmann::json& a = Member(sym, "axis", at);
          const nlohmann::json& o = Member(sym, "offset", at);
          if (!a.is_array() || a.size() != 3 || !o.is_array() || o.size() != 3)
            throw Error(at + ": axis and offset are 3 numbers each");
          axis[k] = Number(a[k], at), offset[k] = Number(o[k], at);
        }
        if (!(axis.norm() > 0)) throw Error(at + ": the axis must not be zero");
        for (int i = 0; i < steps; ++i) {
          continuous.push_back(Eigen::Translation3d(offset) *
                               Eigen::AngleAxisd(2 * M_PI * i / steps, axis.normalized()) *
                               Eigen::Translation3d(-offset));
        }
      }
    }
    for (const Eigen::Isometry3d& d : discrete) {
      if (continuous.empty()) {
        m.symmetry_poses.push_back(d);
      } else {
        for (const Eigen::Isometry3d& c : continuous) m.symmetry_poses.push_back(c * d);
      }
    }
    out.push_back(m);
  }
  return out;
}

std::string BopSceneFolder::Relative(const std::string& name) const {
  return split + "/" + Id6(scene_id) + "/" + name;
}

std::vector<BopSceneFolder> FindBopScenes(const std::filesystem::path& root) {
  namespace fs = std::filesystem;
  std::vector<BopSceneFolder> out;
  std::error_code ec;
  std::vector<fs::path> splits;
  for (const auto& e : fs::directory_iterator(root, ec)) {
    if (e.is_directory(ec) && !e.path().filename().string().starts_with("."))
      splits.push_back(e.path());
  }
  std::sort(splits.begin(), splits.end());
  for (const fs::path& split : splits) {
    std::vector<std::pair<int, fs::path>> scenes;
    for (const auto& e : fs::directory_iterator(split, ec)) {
      const std::string name = e.path().filename().string();
      const std::optional<int> id = ParseBopId(name);
      if (id && name.size() == 6 && e.is_directory(ec)) scenes.push_back({*id, e.path()});
    }
    std::sort(scenes.begin(), scenes.end());
    for (const auto& [id, dir] : scenes) {
      std::vector<std::string> suffixes;
      for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string name = e.path().filename().string();
        if (name.starts_with("scene_camera") && name.ends_with(".json"))
          suffixes.push_back(name.substr(12, name.size() - 12 - 5));
      }
      std::sort(suffixes.begin(), suffixes.end());
      for (const std::string& suffix : suffixes)
        out.push_back({split.filename().string(), id, suffix, dir});
    }
  }
  return out;
}

}  // namespace cadsynth
