#include "cad/mesh_formats.h"

#include <algorithm>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "cad/core/error.h"

namespace cadsynth {

namespace {

using Triangle = Eigen::Matrix<uint32_t, 3, 1>;

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

// A number in `text` in full (no trailing characters), or nothing. Locale-independent.
template <typename T>
std::optional<T> ParseNumber(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  T value{};
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

std::string Shown(std::string_view token) {
  std::string out(token.substr(0, 40));
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  }
  return "'" + out + (token.size() > 40 ? "...'" : "'");
}

// Whitespace-separated tokens of a text, with line numbers for errors.
class Tokens {
 public:
  Tokens(std::string_view text, std::string origin, int first_line = 1)
      : text_(text), origin_(std::move(origin)), line_(first_line) {}

  // The next token, or an empty view at the end. `line()` is then the token's line.
  std::string_view Next() {
    SkipSpace();
    const size_t start = pos_;
    while (pos_ < text_.size() && !IsSpace(text_[pos_])) ++pos_;
    return text_.substr(start, pos_ - start);
  }
  // The next token; throws if the text ends first.
  std::string_view Need(const char* what) {
    const std::string_view token = Next();
    if (token.empty()) Fail("the file ends where " + std::string(what) + " was expected");
    return token;
  }
  // The rest of the current line (without its end), and moves to the next line.
  std::string_view RestOfLine() {
    const size_t start = pos_;
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    std::string_view rest = text_.substr(start, pos_ - start);
    if (pos_ < text_.size()) ++pos_, ++line_;
    return rest;
  }
  bool AtEnd() {
    SkipSpace();
    return pos_ >= text_.size();
  }
  size_t remaining() const { return text_.size() - pos_; }
  int line() const { return line_; }
  [[noreturn]] void Fail(const std::string& message) const {
    // At the end of the text: the last line, not the empty one after its line end.
    int line = line_;
    if (pos_ >= text_.size() && !text_.empty() && text_.back() == '\n' && line > 1) --line;
    throw Error(origin_ + ":" + std::to_string(line) + ": " + message);
  }
  // '#' starts a comment running to the end of its line (OFF).
  void set_hash_comments(bool on) { hash_comments_ = on; }

 private:
  void SkipSpace() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
      } else if (hash_comments_ && c == '#') {
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
        continue;
      } else if (!IsSpace(c)) {
        break;
      }
      ++pos_;
    }
  }

  std::string_view text_;
  std::string origin_;
  size_t pos_ = 0;
  int line_;
  bool hash_comments_ = false;
};

// Triangles of one polygon face (corners already checked against the vertex count).
void AddPolygon(const std::vector<uint32_t>& corners, const std::vector<Eigen::Vector3f>& positions,
                std::vector<Triangle>* triangles) {
  const size_t n = corners.size();
  if (n < 3) return;
  if (n == 4) {
    // Split along 0-2 unless the quad is folded there (concave at 1 or 3): then along 1-3.
    const auto normal = [&](int a, int b, int c) {
      const Eigen::Vector3d pa = positions[corners[a]].cast<double>();
      return (positions[corners[b]].cast<double>() - pa)
          .cross(positions[corners[c]].cast<double>() - pa);
    };
    if (normal(0, 1, 2).dot(normal(0, 2, 3)) < 0) {
      triangles->emplace_back(corners[0], corners[1], corners[3]);
      triangles->emplace_back(corners[1], corners[2], corners[3]);
      return;
    }
  }
  for (size_t i = 1; i + 1 < n; ++i)
    triangles->emplace_back(corners[0], corners[i], corners[i + 1]);
}

// Drops the vertices no triangle uses, keeping the others in order.
Mesh Compacted(std::vector<Eigen::Vector3f> positions, std::vector<Triangle> triangles) {
  std::vector<uint32_t> remap(positions.size(), 0);
  for (const Triangle& t : triangles) remap[t[0]] = remap[t[1]] = remap[t[2]] = 1;
  uint32_t kept = 0;
  for (size_t v = 0; v < positions.size(); ++v) {
    if (remap[v]) {
      positions[kept] = positions[v];
      remap[v] = kept++;
    }
  }
  positions.resize(kept);
  for (Triangle& t : triangles) t = Triangle(remap[t[0]], remap[t[1]], remap[t[2]]);
  Mesh mesh;
  mesh.positions = std::move(positions);
  mesh.triangles = std::move(triangles);
  return mesh;
}

// ---- STL ----------------------------------------------------------------------------------------

uint32_t LoadU32LittleEndian(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return uint32_t{b[0]} | uint32_t{b[1]} << 8 | uint32_t{b[2]} << 16 | uint32_t{b[3]} << 24;
}

Mesh ParseAsciiStl(std::string_view bytes, const std::string& origin) {
  Tokens in(bytes, origin);
  Mesh mesh;
  int corners = -1;  // in a facet: corners so far; -1 outside
  for (std::string_view word = in.Next(); !word.empty(); word = in.Next()) {
    if (word == "solid" || word == "endsolid") {
      in.RestOfLine();  // the solid's name
    } else if (word == "facet") {
      if (corners >= 0) in.Fail("'facet' inside a facet (missing 'endfacet')");
      corners = 0;
      in.RestOfLine();  // its normal: recomputed from the corners
    } else if (word == "outer" || word == "endloop") {
      if (corners < 0) in.Fail(Shown(word) + " outside a facet");
      if (word == "outer" && in.Next() != "loop") in.Fail("expected 'outer loop'");
    } else if (word == "vertex") {
      if (corners < 0) in.Fail("'vertex' outside a facet");
      if (++corners > 3) in.Fail("a facet with more than 3 vertices");
      Eigen::Vector3f p;
      for (int k = 0; k < 3; ++k) {
        const std::string_view token = in.Need("a vertex coordinate");
        const auto value = ParseNumber<float>(token);
        if (!value) in.Fail("expected a number, got " + Shown(token));
        p[k] = *value;
      }
      mesh.positions.push_back(p);
    } else if (word == "endfacet") {
      if (corners != 3) {
        in.Fail(corners < 0 ? "'endfacet' outside a facet"
                            : "a facet with " + std::to_string(corners) + " vertices, not 3");
      }
      const auto base = static_cast<uint32_t>(mesh.positions.size() - 3);
      mesh.triangles.emplace_back(base, base + 1, base + 2);
      corners = -1;
    } else {
      in.Fail("expected facet, vertex or endfacet, got " + Shown(word));
    }
  }
  if (corners >= 0) in.Fail("the file ends inside a facet");
  return mesh;
}

}  // namespace

Mesh ParseStl(std::string_view bytes, const std::string& origin) {
  // Binary: an 80-byte header, a facet count, 50 bytes per facet. Some binary files' headers
  // begin with "solid" too, so an exact size match decides first.
  if (bytes.size() >= 84) {
    const uint64_t count = LoadU32LittleEndian(bytes.data() + 80);
    const uint64_t room = (bytes.size() - 84) / 50;
    const size_t first = bytes.find_first_not_of(" \t\r\n");
    const bool says_solid = first != std::string_view::npos && bytes.substr(first, 5) == "solid";
    if (bytes.size() == 84 + 50 * count && count > 0) {
      // fall through to the binary reader
    } else if (says_solid) {
      return ParseAsciiStl(bytes, origin);
    } else if (count > room) {
      throw Error(origin + ": truncated binary STL: its header says " + std::to_string(count) +
                  " triangles, the file holds " + std::to_string(room));
    }
    if (count > (uint64_t{1} << 32) / 3) {
      throw Error(origin + ": binary STL header says " + std::to_string(count) +
                  " triangles, more than cadsynth reads (1431655765)");
    }
    Mesh mesh;
    mesh.positions.resize(3 * count);
    mesh.triangles.resize(count);
    for (uint64_t f = 0; f < count; ++f) {
      const char* record = bytes.data() + 84 + 50 * f + 12;  // after the facet normal
      for (int c = 0; c < 3; ++c) {
        Eigen::Vector3f& p = mesh.positions[3 * f + c];
        for (int k = 0; k < 3; ++k) {
          p[k] = std::bit_cast<float>(LoadU32LittleEndian(record + 12 * c + 4 * k));
        }
      }
      const auto base = static_cast<uint32_t>(3 * f);
      mesh.triangles[f] = Triangle(base, base + 1, base + 2);
    }
    return mesh;
  }
  const size_t first = bytes.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && bytes.substr(first, 5) == "solid") {
    return ParseAsciiStl(bytes, origin);
  }
  throw Error(origin + ": not an STL file (neither 'solid' text nor a binary header and count)");
}

// ---- PLY ----------------------------------------------------------------------------------------

namespace {

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

std::optional<PlyType> PlyTypeNamed(std::string_view name) {
  static const std::pair<const char*, PlyType> kNames[] = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUint8},
      {"uint8", PlyType::kUint8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUint16},  {"uint16", PlyType::kUint16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUint32},     {"uint32", PlyType::kUint32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  for (const auto& [n, type] : kNames) {
    if (name == n) return type;
  }
  return std::nullopt;
}

size_t PlySize(PlyType type) {
  switch (type) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 8;
}

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::kFloat32;  // of the value, or of a list's items
  bool list = false;
  PlyType count_type = PlyType::kUint8;
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  int line = 0;
  std::vector<PlyProperty> properties;
};

enum class PlyFormat { kAscii, kLittleEndian, kBigEndian };

// Values of a PLY body, one at a time, as doubles.
class PlyValues {
 public:
  PlyValues(std::string_view body, PlyFormat format, const std::string& origin, int first_line)
      : body_(body), format_(format), origin_(origin), tokens_(body, origin, first_line) {}

  double Read(PlyType type, const char* what) {
    if (format_ == PlyFormat::kAscii) {
      const std::string_view token = tokens_.Need(what);
      const auto value = ParseNumber<double>(token);
      if (!value)
        tokens_.Fail("expected a number (" + std::string(what) + "), got " + Shown(token));
      return *value;
    }
    const size_t size = PlySize(type);
    if (body_.size() - pos_ < size) {
      throw Error(origin_ + ": truncated: the file ends in the " + what + " of element '" +
                  element_ + "' " + std::to_string(record_) + " (of the count its header gives)");
    }
    unsigned char b[8];
    std::memcpy(b, body_.data() + pos_, size);
    pos_ += size;
    const bool swap =
        (format_ == PlyFormat::kBigEndian) != (std::endian::native == std::endian::big);
    if (swap) std::reverse(b, b + size);
    switch (type) {
      case PlyType::kInt8:
        return static_cast<int8_t>(b[0]);
      case PlyType::kUint8:
        return b[0];
      case PlyType::kInt16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PlyType::kUint16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PlyType::kInt32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::kUint32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
    }
    return 0;
  }

  // Bytes (binary) or characters (text) left: a bound on how many values can follow.
  size_t remaining() const {
    return format_ == PlyFormat::kAscii ? tokens_.remaining() : body_.size() - pos_;
  }
  void At(const std::string& element, uint64_t record) {
    element_ = element;
    record_ = record;
  }
  [[noreturn]] void Fail(const std::string& message) const {
    if (format_ == PlyFormat::kAscii) tokens_.Fail(message);
    throw Error(origin_ + ": element '" + element_ + "' " + std::to_string(record_) + ": " +
                message);
  }

 private:
  std::string_view body_;
  PlyFormat format_;
  const std::string& origin_;
  Tokens tokens_;
  size_t pos_ = 0;
  std::string element_;
  uint64_t record_ = 0;
};

// A header's "element" line after the keyword: name and count.
PlyElement ParsePlyElementLine(Tokens* words, int line) {
  PlyElement element;
  element.name = std::string(words->Need("an element name"));
  const std::string_view count = words->Need("an element count");
  const auto n = ParseNumber<uint64_t>(count);
  if (!n) words->Fail("element '" + element.name + "': expected a count, got " + Shown(count));
  element.count = *n;
  element.line = line;
  return element;
}

// A header's "property" line after the keyword: [list <count type>] <type> <name>.
PlyProperty ParsePlyPropertyLine(Tokens* words) {
  PlyProperty property;
  std::string_view type = words->Need("a property type");
  if (type == "list") {
    property.list = true;
    const std::string_view count_type = words->Need("a list's count type");
    const auto c = PlyTypeNamed(count_type);
    if (!c || *c == PlyType::kFloat32 || *c == PlyType::kFloat64) {
      words->Fail("a list's count type must be an integer type, got " + Shown(count_type));
    }
    property.count_type = *c;
    type = words->Need("a list's item type");
  }
  const auto t = PlyTypeNamed(type);
  if (!t) words->Fail("unknown property type " + Shown(type));
  property.type = *t;
  property.name = std::string(words->Need("a property name"));
  return property;
}

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  size_t body_start = std::string_view::npos;  // in the file's bytes
  int body_line = 0;
};

// The header: text lines up to "end_header".
PlyHeader ReadPlyHeader(std::string_view bytes, const std::string& origin) {
  Tokens header(bytes, origin);
  if (header.Next() != "ply") header.Fail("not a PLY file (it does not begin with 'ply')");
  header.RestOfLine();
  std::optional<PlyFormat> format;
  PlyHeader out;
  while (out.body_start == std::string_view::npos) {
    if (header.AtEnd()) header.Fail("the header has no 'end_header'");
    const std::string_view keyword = header.Next();
    const int line = header.line();
    Tokens words(header.RestOfLine(), origin, line);
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      out.body_start = bytes.size() - header.remaining();
      out.body_line = line + 1;
      break;
    }
    if (keyword == "format") {
      const std::string_view name = words.Next();
      if (name == "ascii") {
        format = PlyFormat::kAscii;
      } else if (name == "binary_little_endian") {
        format = PlyFormat::kLittleEndian;
      } else if (name == "binary_big_endian") {
        format = PlyFormat::kBigEndian;
      } else {
        words.Fail("unknown PLY format " + Shown(name) +
                   " (ascii, binary_little_endian or binary_big_endian)");
      }
    } else if (keyword == "element") {
      out.elements.push_back(ParsePlyElementLine(&words, line));
    } else if (keyword == "property") {
      if (out.elements.empty()) words.Fail("a property before any element");
      out.elements.back().properties.push_back(ParsePlyPropertyLine(&words));
    } else {
      Tokens(keyword, origin, line).Fail("unknown header line " + Shown(keyword));
    }
  }
  if (!format) throw Error(origin + ": the PLY header has no 'format' line");
  out.format = *format;
  return out;
}

// Which properties hold the geometry: the 'vertex' element (the last, if several) and in *xyz
// the indices of its x, y and z. Refuses elements with records but no properties.
const PlyElement* FindPlyVertex(const std::vector<PlyElement>& elements, const std::string& origin,
                                int xyz[3]) {
  const PlyElement* vertex = nullptr;
  for (const PlyElement& e : elements) {
    if (e.count > 0 && e.properties.empty()) {
      Tokens("", origin, e.line)
          .Fail("element '" + e.name + "' has " + std::to_string(e.count) +
                " records but no properties");
    }
    if (e.name != "vertex") continue;
    vertex = &e;
    for (size_t p = 0; p < e.properties.size(); ++p) {
      for (int k = 0; k < 3; ++k) {
        if (e.properties[p].name == std::string(1, static_cast<char>('x' + k)) &&
            !e.properties[p].list) {
          xyz[k] = static_cast<int>(p);
        }
      }
    }
    if (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0) {
      Tokens("", origin, e.line).Fail("element 'vertex' has no x, y and z properties");
    }
  }
  if (vertex == nullptr) throw Error(origin + ": the PLY file has no 'vertex' element");
  return vertex;
}

// Refuses an element whose header count cannot fit in what is left of the body.
void CheckPlyRoom(const PlyElement& e, PlyFormat format, const PlyValues& values,
                  const std::string& origin) {
  // The smallest a record can be: each value a byte (binary: its size) and a separator.
  size_t min_record = 0;
  for (const PlyProperty& property : e.properties) {
    min_record += format == PlyFormat::kAscii ? 2
                  : property.list             ? PlySize(property.count_type)
                                              : PlySize(property.type);
  }
  if (format == PlyFormat::kAscii && min_record > 0) min_record -= 1;
  if (e.count > values.remaining() / std::max<size_t>(min_record, 1)) {
    throw Error(origin + ":" + std::to_string(e.line) + ": element '" + e.name + "' has " +
                std::to_string(e.count) + " records, more than the " +
                std::to_string(values.remaining()) + " bytes left in the file can hold");
  }
}

// The index of a 'face' element's vertex list property, or -1.
int PlyFaceList(const PlyElement& e) {
  int face_list = -1;
  if (e.name == "face") {
    for (size_t p = 0; p < e.properties.size(); ++p) {
      const PlyProperty& property = e.properties[p];
      if (property.list && (property.name == "vertex_indices" || property.name == "vertex_index"))
        face_list = static_cast<int>(p);
    }
  }
  return face_list;
}

// What reading the body builds up.
struct PlyGeometry {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Triangle> triangles;
  std::vector<uint32_t> corners;  // of the face being read
  bool have_faces = false;
};

// One list property of a record; a face's vertex list (`keep`) becomes triangles.
void ReadPlyList(const PlyProperty& property, bool keep, PlyValues* values, PlyGeometry* geometry) {
  const double count = values->Read(property.count_type, "list length");
  if (count < 0 || count != std::floor(count)) {
    values->Fail("a list length of " + std::to_string(count));
  }
  if (count > static_cast<double>(values->remaining())) {
    values->Fail("truncated: a list of " + std::to_string(static_cast<uint64_t>(count)) +
                 " items, more than the file holds");
  }
  std::vector<uint32_t>& corners = geometry->corners;
  const std::vector<Eigen::Vector3f>& positions = geometry->positions;
  if (keep) corners.clear();
  for (uint64_t i = 0; i < static_cast<uint64_t>(count); ++i) {
    const double index = values->Read(property.type, "list item");
    if (!keep) continue;
    if (!(index >= 0) || index != std::floor(index) ||
        index >= static_cast<double>(positions.size())) {
      values->Fail("face refers to vertex " + std::to_string(index) + ", but the file has " +
                   std::to_string(positions.size()) + " vertices before it");
    }
    corners.push_back(static_cast<uint32_t>(index));
  }
  if (keep) AddPolygon(corners, positions, &geometry->triangles);
}

// The records of one element: the vertex element's give positions, a face element's vertex
// lists triangles; other values are read past.
void ReadPlyRecords(const PlyElement& e, bool is_vertex, const int xyz[3], PlyValues* values,
                    PlyGeometry* geometry) {
  const int face_list = PlyFaceList(e);
  geometry->have_faces = geometry->have_faces || face_list >= 0;
  if (is_vertex) geometry->positions.reserve(e.count);
  for (uint64_t r = 0; r < e.count; ++r) {
    values->At(e.name, r);
    Eigen::Vector3f p = Eigen::Vector3f::Zero();
    for (size_t q = 0; q < e.properties.size(); ++q) {
      const PlyProperty& property = e.properties[q];
      if (!property.list) {
        const double v = values->Read(property.type, "value");
        if (is_vertex) {
          for (int k = 0; k < 3; ++k) {
            if (xyz[k] == static_cast<int>(q)) p[k] = static_cast<float>(v);
          }
        }
        continue;
      }
      ReadPlyList(property, static_cast<int>(q) == face_list, values, geometry);
    }
    if (is_vertex) geometry->positions.push_back(p);
  }
}

}  // namespace

Mesh ParsePly(std::string_view bytes, const std::string& origin) {
  const PlyHeader header = ReadPlyHeader(bytes, origin);
  int xyz[3] = {-1, -1, -1};
  const PlyElement* vertex = FindPlyVertex(header.elements, origin, xyz);

  const std::string_view body = bytes.substr(header.body_start);
  PlyValues values(body, header.format, origin, header.body_line);
  PlyGeometry geometry;
  for (const PlyElement& e : header.elements) {
    CheckPlyRoom(e, header.format, values, origin);
    ReadPlyRecords(e, &e == vertex, xyz, &values, &geometry);
  }
  if (!geometry.have_faces) throw Error(origin + ": the PLY file has no faces (a point cloud?)");
  return Compacted(std::move(geometry.positions), std::move(geometry.triangles));
}

// ---- OFF ----------------------------------------------------------------------------------------

Mesh ParseOff(std::string_view bytes, const std::string& origin) {
  Tokens in(bytes, origin);
  in.set_hash_comments(true);
  // The keyword: [ST][C][N]OFF; 4OFF and nOFF (other dimensions) and binary OFF are refused.
  const std::string_view keyword = in.Next();
  const bool named = keyword.size() >= 3 && keyword.substr(keyword.size() - 3) == "OFF";
  const std::string_view prefix = named ? keyword.substr(0, keyword.size() - 3) : "";
  if (!named || prefix.find_first_not_of("STCN") != std::string_view::npos) {
    in.Fail(named ? "only 3D OFF files are read, not " + Shown(keyword)
                  : "not an OFF file (it does not begin with 'OFF')");
  }
  // Counts may follow on the same line; the rest of a vertex or face line (normals, colours,
  // texture coordinates) is skipped.
  const auto count = [&](const char* what) {
    const std::string_view token = in.Need(what);
    if (token == "BINARY") in.Fail("binary OFF files are not read; write them as text");
    const auto n = ParseNumber<uint64_t>(token);
    if (!n) in.Fail(std::string("expected the ") + what + ", got " + Shown(token));
    return *n;
  };
  const uint64_t vertex_count = count("vertex count");
  const uint64_t face_count = count("face count");
  in.RestOfLine();  // the edge count, often present, not used
  // A vertex takes at least three numbers (6 characters), a face at least one.
  if (vertex_count > in.remaining() / 6 || face_count > in.remaining() / 2) {
    in.Fail("the header's " + std::to_string(vertex_count) + " vertices and " +
            std::to_string(face_count) + " faces cannot fit in the " +
            std::to_string(in.remaining()) + " bytes that follow");
  }
  std::vector<Eigen::Vector3f> positions(vertex_count);
  const auto number = [&](const char* what) {
    const std::string_view token = in.Next();
    if (token.empty()) {
      in.Fail("the file ends in its " + std::string(what) + " (the header gives " +
              std::to_string(vertex_count) + " vertices and " + std::to_string(face_count) +
              " faces)");
    }
    const auto value = ParseNumber<double>(token);
    if (!value) in.Fail("expected a number (" + std::string(what) + "), got " + Shown(token));
    return *value;
  };
  for (Eigen::Vector3f& p : positions) {
    for (int k = 0; k < 3; ++k) p[k] = static_cast<float>(number("vertex list"));
    in.RestOfLine();
  }
  std::vector<Triangle> triangles;
  std::vector<uint32_t> corners;
  for (uint64_t f = 0; f < face_count; ++f) {
    const double n = number("face list");
    if (n < 0 || n != std::floor(n) || n > static_cast<double>(in.remaining())) {
      in.Fail("face " + std::to_string(f) + " has " + std::to_string(n) + " corners");
    }
    corners.clear();
    for (uint64_t i = 0; i < static_cast<uint64_t>(n); ++i) {
      const double index = number("face list");
      if (!(index >= 0) || index != std::floor(index) ||
          index >= static_cast<double>(vertex_count)) {
        in.Fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(index) +
                ", but the file has " + std::to_string(vertex_count));
      }
      corners.push_back(static_cast<uint32_t>(index));
    }
    in.RestOfLine();
    AddPolygon(corners, positions, &triangles);
  }
  return Compacted(std::move(positions), std::move(triangles));
}

bool HasCheckedMeshReader(const std::string& extension) {
  return extension == ".stl" || extension == ".ply" || extension == ".off";
}

Mesh ParseMeshBytes(std::string_view bytes, const std::string& extension,
                    const std::string& origin) {
  if (extension == ".stl") return ParseStl(bytes, origin);
  if (extension == ".ply") return ParsePly(bytes, origin);
  if (extension == ".off") return ParseOff(bytes, origin);
  throw Error(origin + ": no checked reader for '" + extension + "' files");
}

}  // namespace cadsynth
