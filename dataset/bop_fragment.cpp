// The scene writer's journal: a frame's fragment, composed for WriteFrame and parsed (every line
// checked) for Finish, CheckFrame, merge and the fuzz harness, and BopSceneWriter's resume half:
// which frames are written, whether their files are intact, forgetting a damaged one.
#include "dataset/bop_fragment.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <mutex>
#include <system_error>

#include "cad/core/error.h"
#include "dataset/bop.h"
#include "dataset/bop_read.h"

namespace cadsynth {
namespace bop_internal {

Fragment ParseFragmentText(const std::string& text, const std::string& origin) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < text.size() && lines.size() < 6) {
    const size_t end = text.find('\n', start);
    if (end == std::string::npos) break;
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  if (lines.size() < 5)
    throw Error(origin + ": incomplete fragment (" + std::to_string(lines.size()) + " of 5 lines)");
  Json parsed[5];
  for (int i = 0; i < 5; ++i) {
    try {
      parsed[i] = Json::parse(lines[i]);
    } catch (const Json::exception&) {
      throw Error(origin + ":" + std::to_string(i + 1) + ": not valid JSON");
    }
  }
  const auto fail = [&](int line, const std::string& what) {
    throw Error(origin + ":" + std::to_string(line) + ": " + what);
  };
  const auto is_id = [](const Json& v) {
    return v.is_number_integer() && v.get<int64_t>() >= 0 && v.get<int64_t>() <= 2147483647;
  };
  Fragment f;
  f.camera = std::move(parsed[0]);
  if (!f.camera.is_object()) fail(1, "the camera entry is not an object");
  f.gt = std::move(parsed[1]);
  if (!f.gt.is_array()) fail(2, "the ground-truth entry is not a list");
  for (const Json& g : f.gt) {
    if (!g.is_object() || !g.contains("obj_id") || !is_id(g["obj_id"]))
      fail(2, "an instance without an obj_id");
  }
  f.gt_info = std::move(parsed[2]);
  if (!f.gt_info.is_array()) fail(3, "the visibility entry is not a list");
  for (const Json& g : f.gt_info) {
    if (!g.is_object() || !g.contains("visib_fract") || !g["visib_fract"].is_number())
      fail(3, "an instance without a visib_fract number");
  }
  f.coco = std::move(parsed[3]);
  if (!f.coco.is_object() || !f.coco.contains("width") || !is_id(f.coco["width"]) ||
      !f.coco.contains("height") || !is_id(f.coco["height"]) || !f.coco.contains("annotations") ||
      !f.coco["annotations"].is_array()) {
    fail(4, "the COCO entry lacks width, height or annotations");
  }
  for (const Json& a : f.coco["annotations"]) {
    if (!a.is_object()) fail(4, "an annotation is not an object");
    for (const char* key : {"inst_id", "obj_id", "area"}) {
      if (!a.contains(key) || !is_id(a[key])) fail(4, std::string("an annotation without ") + key);
    }
    if (!a.contains("bbox") || !a["bbox"].is_array() || !a.contains("ignore") ||
        !a["ignore"].is_boolean() || !a.contains("counts") || !a["counts"].is_string()) {
      fail(4, "an annotation without bbox, ignore or counts");
    }
  }
  const Json& manifest = parsed[4];
  if (!manifest.is_object() || !manifest.contains("files") || !manifest["files"].is_array())
    fail(5, "the manifest has no file list");
  for (const Json& file : manifest["files"]) {
    if (!file.is_array() || file.size() != 3 || !file[0].is_string() ||
        !file[1].is_number_unsigned() || !file[2].is_number_unsigned() ||
        file[2].get<uint64_t>() > 0xffffffffu) {
      fail(5, "a manifest record is not [path, size, crc32]");
    }
    const std::string path = file[0].get<std::string>();
    if (path.empty() || path[0] == '/' || path.find("..") != std::string::npos)
      fail(5, "a manifest path leaves the dataset: " + path.substr(0, 80));
    f.files.push_back({path, file[1].get<uint64_t>(), file[2].get<uint32_t>()});
  }
  if (lines.size() == 6) {
    try {
      f.randomization = Json::parse(lines[5]);
    } catch (const Json::exception&) {
      fail(6, "not valid JSON");
    }
    if (!f.randomization.is_object()) fail(6, "the randomisation record is not an object");
  }
  return f;
}

Fragment ReadFragment(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return ParseFragmentText(text, path.string());
}

std::string FragmentText(const Json& camera, const Json& gt, const Json& gt_info, int width,
                         int height, const Json& coco_annotations,
                         const std::vector<FileRecord>& files, const std::string& randomization) {
  Json manifest = Json::array();
  for (const FileRecord& r : files) manifest.push_back({r.path, r.size, r.crc32});
  return camera.dump() + "\n" + gt.dump() + "\n" + gt_info.dump() + "\n" +
         Json{{"width", width}, {"height", height}, {"annotations", coco_annotations}}.dump() +
         "\n" + Json{{"files", manifest}}.dump() + "\n" +
         (randomization.empty() ? std::string() : Json::parse(randomization).dump() + "\n");
}

std::vector<int> FragmentIds(const std::filesystem::path& folder) {
  std::vector<int> ids;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    if (name.size() != 11 || name.substr(6) != ".json") continue;
    if (const auto id = ParseBopId(name.substr(0, 6))) ids.push_back(*id);
  }
  return ids;
}

}  // namespace bop_internal

using bop_internal::Fragment;
using bop_internal::ParseFragmentText;
using bop_internal::ReadFragment;

void CheckFragmentText(const std::string& text, const std::string& origin) {
  ParseFragmentText(text, origin);
}

std::filesystem::path BopSceneWriter::FragmentPath(int image_id) const {
  return Folder(".fragments") / (Id6(image_id) + ".json");
}

bool BopSceneWriter::HasFrame(int image_id) const {
  return std::filesystem::exists(FragmentPath(image_id));
}

std::vector<int> BopSceneWriter::WrittenFrames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<int> ids = image_ids_;
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

std::string BopSceneWriter::CheckFrame(int image_id) const {
  const std::filesystem::path path = FragmentPath(image_id);
  Fragment fragment;
  try {
    fragment = ReadFragment(path);
  } catch (const Error& e) {
    return e.what();
  }
  for (const FileRecord& record : fragment.files) {
    const std::string problem = CheckFile(root_, record);
    if (!problem.empty()) return (root_ / record.path).string() + ": " + problem;
  }
  return {};
}

void BopSceneWriter::ForgetFrame(int image_id) {
  std::error_code ec;
  std::filesystem::remove(FragmentPath(image_id), ec);
  if (ec)
    throw Error(Folder(".fragments").string() + ": cannot remove the record of image " +
                std::to_string(image_id) + ": " + ec.message());
  std::lock_guard<std::mutex> lock(mutex_);
  image_ids_.erase(std::remove(image_ids_.begin(), image_ids_.end(), image_id), image_ids_.end());
}

void BopSceneWriter::RemoveFragments() {
  std::error_code ec;
  std::filesystem::remove_all(Folder(".fragments"), ec);
}

}  // namespace cadsynth
