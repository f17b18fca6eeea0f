#include "cad/step_tessellated.h"

#include <cctype>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "cad/core/error.h"
#include "cad/mesh_analysis.h"

namespace cadsynth::internal {
namespace {

// One parameter of a STEP record.
struct Param {
  enum Kind { kNull, kNumber, kString, kRef, kEnum, kList } kind = kNull;
  double number = 0.0;
  long ref = 0;
  std::string text;
  std::vector<Param> list;
};

struct Record {
  std::string type;  // empty for complex (multi-type) entities, which we do not need
  std::vector<Param> params;
};

class Parser {
 public:
  Parser(const std::string& text, const std::string& file) : s_(text), file_(file) {}

  std::unordered_map<long, Record> Records() {
    std::unordered_map<long, Record> records;
    const size_t data = s_.find("DATA;");
    if (data == std::string::npos) Fail("no DATA section");
    i_ = data + 5;
    while (true) {
      Skip();
      if (i_ >= s_.size()) Fail("the DATA section does not end (no ENDSEC)");
      if (s_.compare(i_, 7, "ENDSEC;") == 0) break;
      if (s_[i_] != '#') Fail("expected an entity '#N='");
      ++i_;
      const long id = Integer();
      Skip();
      Expect('=');
      Skip();
      Record record;
      if (s_[i_] == '(') {  // complex entity: skip to the end of the record
        SkipBalanced();
      } else {
        record.type = Keyword();
        Skip();
        Expect('(');
        record.params = List(')');
      }
      Skip();
      Expect(';');
      records.emplace(id, std::move(record));
    }
    return records;
  }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    const size_t line =
        static_cast<size_t>(std::count(s_.begin(), s_.begin() + std::min(i_, s_.size()), '\n')) + 1;
    throw Error(file_ + ": line " + std::to_string(line) + ": " + what);
  }
  void Skip() {
    while (i_ < s_.size()) {
      if (std::isspace(static_cast<unsigned char>(s_[i_]))) {
        ++i_;
      } else if (s_.compare(i_, 2, "/*") == 0) {
        const size_t end = s_.find("*/", i_ + 2);
        if (end == std::string::npos) Fail("unterminated comment");
        i_ = end + 2;
      } else {
        break;
      }
    }
  }
  void Expect(char c) {
    if (i_ >= s_.size() || s_[i_] != c) Fail(std::string("expected '") + c + "'");
    ++i_;
  }
  long Integer() {
    const size_t start = i_;
    while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
    if (start == i_) Fail("expected a number");
    if (i_ - start > 18) Fail("a number too large");  // std::stol would throw out_of_range
    return std::stol(s_.substr(start, i_ - start));
  }
  std::string Keyword() {
    const size_t start = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_'))
      ++i_;
    if (start == i_) Fail("expected an entity type");
    return s_.substr(start, i_ - start);
  }
  void SkipBalanced() {
    int depth = 0;
    do {
      if (i_ >= s_.size()) Fail("unbalanced parentheses");
      if (s_[i_] == '\'') {
        String();
        continue;
      }
      if (s_[i_] == '(') ++depth;
      if (s_[i_] == ')') --depth;
      ++i_;
    } while (depth > 0);
  }
  std::string String() {
    ++i_;  // opening quote
    std::string out;
    while (true) {
      if (i_ >= s_.size()) Fail("unterminated string");
      if (s_[i_] == '\'') {
        if (i_ + 1 < s_.size() && s_[i_ + 1] == '\'') {
          out += '\'';
          i_ += 2;
          continue;
        }
        ++i_;
        return out;
      }
      out += s_[i_++];
    }
  }
  std::vector<Param> List(char close) {
    // Lists nest by recursion: bounded, so a hostile file cannot exhaust the stack.
    if (++depth_ > 1000) Fail("lists nested more than 1000 deep");
    struct Leave {
      int& depth;
      ~Leave() { --depth; }
    } leave{depth_};
    std::vector<Param> params;
    Skip();
    if (i_ < s_.size() && s_[i_] == close) {
      ++i_;
      return params;
    }
    while (true) {
      Skip();
      params.push_back(Value());
      Skip();
      if (i_ >= s_.size()) Fail("unterminated parameter list");
      if (s_[i_] == ',') {
        ++i_;
        continue;
      }
      Expect(close);
      return params;
    }
  }
  Param Value() {
    Param p;
    if (i_ >= s_.size()) Fail("missing parameter");
    const char c = s_[i_];
    if (c == '$' || c == '*') {
      ++i_;
    } else if (c == '#') {
      ++i_;
      p.kind = Param::kRef;
      p.ref = Integer();
    } else if (c == '\'') {
      p.kind = Param::kString;
      p.text = String();
    } else if (c == '.') {
      const size_t end = s_.find('.', i_ + 1);
      if (end == std::string::npos) Fail("unterminated enumeration");
      p.kind = Param::kEnum;
      p.text = s_.substr(i_ + 1, end - i_ - 1);
      i_ = end + 1;
    } else if (c == '(') {
      ++i_;
      p.kind = Param::kList;
      p.list = List(')');
    } else if (std::isalpha(
                   static_cast<unsigned char>(c))) {  // typed value, e.g. LENGTH_MEASURE(1.)
      Keyword();
      Skip();
      Expect('(');
      std::vector<Param> inner = List(')');
      if (inner.size() == 1) p = inner[0];
    } else {
      const char* begin = s_.c_str() + i_;
      char* end = nullptr;
      p.number = std::strtod(begin, &end);
      if (end == begin) Fail(std::string("unexpected character '") + c + "'");
      p.kind = Param::kNumber;
      i_ += static_cast<size_t>(end - begin);
    }
    return p;
  }

  const std::string& s_;
  const std::string& file_;
  size_t i_ = 0;
  int depth_ = 0;
};

struct Face {
  std::vector<Eigen::Vector3f> points;        // positions of the face's points (via pnindex)
  std::vector<Eigen::Vector3f> normals;       // one per point, or empty
  std::vector<std::array<int, 3>> triangles;  // 0-based into points
};

// Reads a (COMPLEX_)TRIANGULATED_FACE into points and triangles.
Face ReadFace(const Record& face, const std::unordered_map<long, Record>& records,
              const std::string& file, long id) {
  const auto fail = [&](const std::string& what) -> void {
    throw Error(file + ": #" + std::to_string(id) + " " + face.type + ": " + what);
  };
  Face out;
  if (face.params.size() < 7 || face.params[1].kind != Param::kRef) fail("too few parameters");
  const auto coords = records.find(face.params[1].ref);
  if (coords == records.end() || coords->second.type != "COORDINATES_LIST" ||
      coords->second.params.size() < 3) {
    fail("its coordinates are not a COORDINATES_LIST");
  }
  const std::vector<Param>& xyz = coords->second.params[2].list;
  const std::vector<Param>& pnindex = face.params[5].list;
  const size_t count = pnindex.empty() ? xyz.size() : pnindex.size();
  for (size_t k = 0; k < count; ++k) {
    const long index =
        pnindex.empty() ? static_cast<long>(k) + 1 : static_cast<long>(pnindex[k].number);
    if (index < 1 || static_cast<size_t>(index) > xyz.size() || xyz[index - 1].list.size() != 3) {
      fail("point index " + std::to_string(index) + " is outside its coordinates list");
    }
    const auto& p = xyz[index - 1].list;
    out.points.emplace_back(float(p[0].number), float(p[1].number), float(p[2].number));
  }
  const std::vector<Param>& normals = face.params[3].list;
  if (normals.size() == out.points.size() || normals.size() == 1) {
    for (size_t k = 0; k < out.points.size(); ++k) {
      const auto& n = normals[normals.size() == 1 ? 0 : k].list;
      if (n.size() == 3)
        out.normals.emplace_back(float(n[0].number), float(n[1].number), float(n[2].number));
    }
    if (out.normals.size() != out.points.size()) out.normals.clear();
  }
  const auto index = [&](const Param& p) {
    const long i = static_cast<long>(p.number);
    if (i < 1 || static_cast<size_t>(i) > out.points.size())
      fail("triangle index " + std::to_string(i) + " out of range");
    return static_cast<int>(i - 1);
  };
  const auto add = [&](int a, int b, int c) {
    if (a != b && b != c && a != c)
      out.triangles.push_back({a, b, c});  // repeated indices: strip joins
  };
  if (face.type == "TRIANGULATED_FACE") {
    for (const Param& t : face.params[6].list) {
      if (t.list.size() != 3) fail("a triangle without three indices");
      add(index(t.list[0]), index(t.list[1]), index(t.list[2]));
    }
  } else {
    for (const Param& strip :
         face.params[6].list) {  // each new point closes a triangle, alternating
      for (size_t k = 2; k < strip.list.size(); ++k) {
        const int a = index(strip.list[k - 2]), b = index(strip.list[k - 1]),
                  c = index(strip.list[k]);
        if (k % 2 == 0)
          add(a, b, c);
        else
          add(b, a, c);
      }
    }
    if (face.params.size() > 7) {
      for (const Param& fan : face.params[7].list) {
        for (size_t k = 2; k < fan.list.size(); ++k) {
          add(index(fan.list[0]), index(fan.list[k - 1]), index(fan.list[k]));
        }
      }
    }
  }
  return out;
}

// The first COLOUR_RGB reachable from a styling record (STYLED_ITEM -> ... -> COLOUR_RGB).
std::optional<Eigen::Vector3f> FindColour(long id, const std::unordered_map<long, Record>& records,
                                          int depth) {
  const auto it = records.find(id);
  if (it == records.end() || depth > 8) return std::nullopt;
  const Record& r = it->second;
  if (r.type == "COLOUR_RGB" && r.params.size() >= 4) {
    return Eigen::Vector3f(float(r.params[1].number), float(r.params[2].number),
                           float(r.params[3].number));
  }
  std::vector<const Param*> stack;
  for (const Param& p : r.params) stack.push_back(&p);
  while (!stack.empty()) {
    const Param* p = stack.back();
    stack.pop_back();
    if (p->kind == Param::kRef) {
      if (auto c = FindColour(p->ref, records, depth + 1)) return c;
    } else if (p->kind == Param::kList) {
      for (const Param& q : p->list) stack.push_back(&q);
    }
  }
  return std::nullopt;
}

}  // namespace

Assembly ReadStepTessellated(const std::filesystem::path& path, double unit_mm) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  Assembly assembly;
  if (text.find("TESSELLATED_SOLID") == std::string::npos &&
      text.find("TESSELLATED_SHELL") == std::string::npos) {
    return assembly;
  }
  const std::unordered_map<long, Record> records = Parser(text, file).Records();

  // Colours of styled faces.
  std::unordered_map<long, Eigen::Vector3f> colour_of;
  for (const auto& [id, r] : records) {
    if (r.type != "STYLED_ITEM" || r.params.size() < 3 || r.params[2].kind != Param::kRef) continue;
    if (auto c = FindColour(id, records, 0)) colour_of[r.params[2].ref] = *c;
  }

  // Construction planes and the like ("supplemental geometry") are not part of the object.
  std::unordered_set<long> constructive;
  for (const auto& [id, r] : records) {
    if (r.type != "CONSTRUCTIVE_GEOMETRY_REPRESENTATION" || r.params.size() < 2) continue;
    for (const Param& item : r.params[1].list) constructive.insert(item.ref);
  }
  std::vector<long> solids;
  for (const auto& [id, r] : records) {
    if ((r.type == "TESSELLATED_SOLID" || r.type == "TESSELLATED_SHELL") &&
        !constructive.count(id)) {
      solids.push_back(id);
    }
  }
  std::sort(solids.begin(), solids.end());  // file order, whatever the hash map's
  for (long id : solids) {
    const Record& solid = records.at(id);
    Part part;
    part.name = solid.params.empty() || solid.params[0].text.empty()
                    ? "tessellated_" + std::to_string(id)
                    : solid.params[0].text;
    std::map<std::array<float, 3>, size_t> colour_votes;
    if (solid.params.size() < 2)
      throw Error(file + ": #" + std::to_string(id) + " " + solid.type + ": no faces");
    for (const Param& item : solid.params[1].list) {
      const auto face_record = records.find(item.ref);
      if (item.kind != Param::kRef || face_record == records.end()) continue;
      const std::string& type = face_record->second.type;
      if (type != "TRIANGULATED_FACE" && type != "COMPLEX_TRIANGULATED_FACE") continue;
      const Face face = ReadFace(face_record->second, records, file, item.ref);
      const auto base = static_cast<uint32_t>(part.mesh.positions.size());
      for (const Eigen::Vector3f& p : face.points)
        part.mesh.positions.push_back(p * float(unit_mm));
      for (const auto& t : face.triangles) {
        Eigen::Matrix<uint32_t, 3, 1> tri(base + t[0], base + t[1], base + t[2]);
        if (!face.normals.empty()) {  // wind to agree with the file's normals
          const Eigen::Vector3f n =
              (face.points[t[1]] - face.points[t[0]]).cross(face.points[t[2]] - face.points[t[0]]);
          if (n.dot(face.normals[t[0]] + face.normals[t[1]] + face.normals[t[2]]) < 0)
            std::swap(tri[1], tri[2]);
        }
        part.mesh.triangles.push_back(tri);
      }
      // Normals: the file's, else the faces' own (area-weighted).
      std::vector<Eigen::Vector3f> normals = face.normals;
      if (normals.empty()) {
        normals.assign(face.points.size(), Eigen::Vector3f::Zero());
        for (size_t k = part.mesh.triangles.size() - face.triangles.size();
             k < part.mesh.triangles.size(); ++k) {
          const auto& tri = part.mesh.triangles[k];
          const Eigen::Vector3f& a = part.mesh.positions[tri[0]];
          const Eigen::Vector3f n =
              (part.mesh.positions[tri[1]] - a).cross(part.mesh.positions[tri[2]] - a);
          for (int c = 0; c < 3; ++c) normals[tri[c] - base] += n;
        }
      }
      for (Eigen::Vector3f n : normals)
        part.mesh.normals.push_back(n.norm() > 0 ? n.normalized() : Eigen::Vector3f::UnitZ());
      const auto colour = colour_of.find(item.ref);
      if (colour != colour_of.end()) {
        colour_votes[{colour->second.x(), colour->second.y(), colour->second.z()}] +=
            face.triangles.size();
      }
    }
    if (part.mesh.empty()) continue;
    if (!colour_votes.empty()) {
      const auto best =
          std::max_element(colour_votes.begin(), colour_votes.end(),
                           [](const auto& a, const auto& b) { return a.second < b.second; });
      part.color = Eigen::Vector3f(best->first[0], best->first[1], best->first[2]);
    }
    const Eigen::Vector3d centre = part.mesh.Bounds().center();
    part.cad_from_model = Eigen::Translation3d(centre);
    part.mesh.Transform(part.cad_from_model.inverse());
    part.watertight = AnalyzeTopology(part.mesh).watertight();
    if (part.watertight) part.mass = ComputeMeshMassProperties(part.mesh);
    assembly.instances.push_back(
        Instance{static_cast<int>(assembly.parts.size()), part.name, part.cad_from_model});
    assembly.parts.push_back(std::move(part));
  }
  return assembly;
}

}  // namespace cadsynth::internal
