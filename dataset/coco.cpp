// COCO: run-length encoding (dataset/coco.h) and the merged coco/{train,test}.json (declared in
// dataset/bop.h: it reads the scenes' scene_gt_coco.json that BopSceneWriter::Finish writes).
#include "dataset/coco.h"

#include <algorithm>
#include <fstream>
#include <map>
#include <system_error>

#include "cad/core/error.h"
#include "dataset/bop.h"
#include "dataset/bop_internal.h"
#include "dataset/file_io.h"

namespace cadsynth {

std::string CompressRleCounts(const std::vector<uint32_t>& counts) {
  std::string out;
  for (size_t i = 0; i < counts.size(); ++i) {
    int64_t x = counts[i];
    if (i > 2) x -= counts[i - 2];
    for (bool more = true; more;) {
      char c = static_cast<char>(x & 0x1f);
      x >>= 5;  // arithmetic: negative differences end in all ones
      more = (c & 0x10) ? x != -1 : x != 0;
      if (more) c |= 0x20;
      out += static_cast<char>(c + 48);
    }
  }
  return out;
}

std::vector<uint32_t> DecompressRleCounts(const std::string& text) {
  std::vector<uint32_t> counts;
  size_t p = 0;
  while (p < text.size()) {
    int64_t x = 0;
    int k = 0;
    for (bool more = true; more; ++k) {
      if (p >= text.size() || text[p] < 48 || text[p] > 48 + 63 || k > 12) {
        throw Error("RLE counts: malformed string at character " + std::to_string(p));
      }
      const int c = text[p++] - 48;
      x |= static_cast<int64_t>(c & 0x1f) << (5 * k);
      more = (c & 0x20) != 0;
      if (!more && (c & 0x10)) x |= -(int64_t{1} << (5 * (k + 1)));
    }
    if (counts.size() > 2) x += counts[counts.size() - 2];
    if (x < 0) throw Error("RLE counts: negative run");
    counts.push_back(static_cast<uint32_t>(x));
  }
  return counts;
}

std::vector<uint8_t> DecodeRle(const RleMask& rle) {
  const size_t n = static_cast<size_t>(rle.height) * rle.width;
  std::vector<uint8_t> mask(n, 0);
  size_t pos = 0;
  for (size_t i = 0; i < rle.counts.size(); ++i) {
    if (pos + rle.counts[i] > n) throw Error("RLE: runs exceed the image");
    for (uint32_t j = 0; j < rle.counts[i]; ++j, ++pos) {
      if (i % 2 == 1) {
        const size_t u = pos / rle.height, v = pos % rle.height;
        mask[v * rle.width + u] = 1;
      }
    }
  }
  if (pos != n)
    throw Error("RLE: runs cover " + std::to_string(pos) + " of " + std::to_string(n) + " pixels");
  return mask;
}

using bop_internal::Json;

void WriteMergedCoco(const std::filesystem::path& root, const BopOptions& options,
                     const std::vector<SceneSplit>& scenes, const std::vector<ObjectClass>& classes,
                     const BopSensor& sensor) {
  if (!options.coco) return;
  const std::string sfx = sensor.Suffix();
  CreateFolder(root / "coco");
  Json categories = Json::array();
  std::map<int, std::string> class_names;
  for (const ObjectClass& c : classes) class_names[c.id] = c.name;
  for (const auto& [id, name] : class_names)
    categories.push_back({{"id", id}, {"name", name}, {"supercategory", "cadsynth"}});
  // Streamed, so that memory does not grow with the dataset: the scene files are read as
  // Finish() writes them (one annotation per line, the image list on one line), annotations in
  // a first pass over the scenes and images in a second. Images are numbered from 1 in scene
  // order, then image order; an image's number is its rank in its scene's (sorted) split list.
  const auto scene_file = [&](size_t s) {
    return root / options.split / Id6(static_cast<int>(s)) / ("scene_gt_coco" + sfx + ".json");
  };
  const auto strip = [](std::string line) {  // "    {...}," -> "{...}"
    const size_t begin = line.find_first_not_of(' ');
    while (!line.empty() && (line.back() == ',' || line.back() == '\r')) line.pop_back();
    return begin == std::string::npos ? std::string() : line.substr(begin);
  };
  for (const bool test : {false, true}) {
    const std::filesystem::path path =
        root / "coco" / (std::string(test ? "test" : "train") + sfx + ".json");
    const std::string temporary = path.string() + ".tmp";
    std::ofstream out(temporary, std::ios::binary);
    if (!out) throw Error(path.string() + ": cannot create file");
    out << "{\"annotations\":[";
    size_t annotation_count = 0, image_base = 0;
    for (size_t s = 0; s < scenes.size(); ++s) {
      const std::vector<int>& wanted = test ? scenes[s].test : scenes[s].train;
      if (wanted.empty()) continue;
      std::ifstream in(scene_file(s), std::ios::binary);
      if (!in) throw Error(scene_file(s).string() + ": cannot open");
      std::string line;
      bool in_annotations = false;
      while (std::getline(in, line)) {
        if (line.rfind("  \"annotations\": [", 0) == 0) {
          in_annotations = true;
          continue;
        }
        if (!in_annotations) continue;
        if (line.rfind("  ]", 0) == 0 || line.rfind("  \"", 0) == 0) break;
        const std::string text = strip(line);
        if (text.empty()) continue;
        Json a;
        try {
          a = Json::parse(text);
        } catch (const Json::exception& e) {
          throw Error(scene_file(s).string() + ": unreadable annotation: " + e.what());
        }
        const int im = a["image_id"];
        const auto found = std::lower_bound(wanted.begin(), wanted.end(), im);
        if (found == wanted.end() || *found != im) continue;
        const int obj = a["category_id"];
        a["id"] = static_cast<int>(++annotation_count);
        a["image_id"] = static_cast<int>(image_base + (found - wanted.begin()) + 1);
        a["category_id"] =
            obj >= 1 && obj <= static_cast<int>(classes.size()) ? classes[obj - 1].id : obj;
        a["obj_id"] = obj;
        a["scene_id"] = s;
        a["im_id"] = im;
        out << (annotation_count == 1 ? "" : ",") << a.dump();
      }
      image_base += wanted.size();
    }
    out << "],\"categories\":" << categories.dump() << ",\"images\":[";
    size_t image_count = 0;
    for (size_t s = 0; s < scenes.size(); ++s) {
      const std::vector<int>& wanted = test ? scenes[s].test : scenes[s].train;
      if (wanted.empty()) continue;
      std::ifstream in(scene_file(s), std::ios::binary);
      std::string line;
      Json images;
      while (std::getline(in, line)) {
        if (line.rfind("  \"images\": ", 0) != 0) continue;
        images = Json::parse(strip(line.substr(12)), nullptr, false);
        break;
      }
      if (!images.is_array()) throw Error(scene_file(s).string() + ": no readable image list");
      const std::string scene_folder = options.split + "/" + Id6(static_cast<int>(s));
      size_t listed = 0;
      for (const Json& image : images) {
        const int im = image["id"];
        if (!std::binary_search(wanted.begin(), wanted.end(), im)) continue;
        ++listed;
        out << (image_count++ == 0 ? "" : ",")
            << Json{{"id", image_count},
                    {"file_name", scene_folder + "/" + image["file_name"].get<std::string>()},
                    {"width", image["width"]},
                    {"height", image["height"]},
                    {"scene_id", s},
                    {"im_id", im}}
                   .dump();
      }
      if (listed != wanted.size()) {
        throw Error(scene_file(s).string() + ": lists " + std::to_string(listed) + " of the " +
                    std::to_string(wanted.size()) + " images of its split");
      }
    }
    out << "],\"info\":"
        << Json{{"description", test ? "cadsynth test split" : "cadsynth train split"}}.dump()
        << ",\"licenses\":[]}\n";
    out.close();
    if (!out) throw Error(path.string() + ": cannot write file (disk full?)");
    std::error_code ec;
    std::filesystem::rename(temporary, path, ec);
    if (ec) throw Error(path.string() + ": cannot move file into place: " + ec.message());
  }
}

}  // namespace cadsynth
