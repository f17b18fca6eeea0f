#include "dataset/manifest.h"

#include <algorithm>
#include <sstream>
#include <system_error>

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include "cad/core/error.h"
#include "dataset/bop_read.h"

namespace cadsynth {

namespace fs = std::filesystem;

bool IsDatasetContent(const fs::path& relative) {
  for (const fs::path& part : relative) {
    const std::string name = part.string();
    if (name.empty() || name[0] == '.') return false;
  }
  const std::string text = relative.generic_string();
  return text != kManifestFile && text != kRunRecordFile && text != kCertificateFile &&
         text != kReportFile;
}

std::vector<FileRecord> ListDatasetFiles(const fs::path& root) {
  std::vector<FileRecord> files;
  std::error_code ec;
  fs::recursive_directory_iterator it(root, ec), end;
  if (ec) throw Error(root.string() + ": cannot list: " + ec.message());
  for (; it != end; it.increment(ec)) {
    if (ec) throw Error(root.string() + ": cannot list: " + ec.message());
    const fs::path relative = it->path().lexically_relative(root);
    if (it->is_directory(ec)) {
      if (!relative.empty() && relative.filename().string().starts_with("."))
        it.disable_recursion_pending();
      continue;
    }
    if (!it->is_regular_file(ec) || !IsDatasetContent(relative)) continue;
    files.push_back({relative.generic_string(), 0, 0});
  }
  std::sort(files.begin(), files.end(),
            [](const FileRecord& a, const FileRecord& b) { return a.path < b.path; });
  tbb::parallel_for(size_t{0}, files.size(), [&](size_t i) {
    const std::string bytes = ReadFileText(root / files[i].path);
    files[i].size = bytes.size();
    files[i].crc32 = Crc32(bytes);
  });
  return files;
}

void WriteManifest(const fs::path& root, const DatasetManifest& manifest) {
  std::ostringstream out;
  out << "{\n  \"cadsynth_manifest\": 1,\n  \"version\": "
      << nlohmann::json(manifest.version).dump()
      << ",\n  \"run_key\": " << nlohmann::json(manifest.run_key).dump()
      << ",\n  \"frames\": " << manifest.frames << ",\n  \"files\": [";
  for (size_t i = 0; i < manifest.files.size(); ++i) {
    const FileRecord& f = manifest.files[i];
    out << (i ? ",\n    [" : "\n    [") << nlohmann::json(f.path).dump() << ", " << f.size << ", "
        << f.crc32 << "]";
  }
  out << (manifest.files.empty() ? "]\n}\n" : "\n  ]\n}\n");
  WriteFileAtomic(root / kManifestFile, out.str());
}

DatasetManifest ReadManifest(const fs::path& root) {
  const fs::path path = root / kManifestFile;
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw Error(path.string() +
                ": missing: the dataset is unfinished (its run or merge did not end) or older than "
                "manifests");
  const std::string text = ReadFileText(path);
  DatasetManifest m;
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    if (j.at("cadsynth_manifest").get<int>() != 1)
      throw Error(path.string() + ": cadsynth_manifest: unknown version " +
                  j.at("cadsynth_manifest").dump());
    m.version = j.at("version").get<std::string>();
    m.run_key = j.at("run_key").get<std::string>();
    m.frames = j.at("frames").get<size_t>();
    for (const nlohmann::json& f : j.at("files")) {
      if (!f.is_array() || f.size() != 3)
        throw Error(path.string() + ": files: each entry is [path, size, crc32], not " + f.dump());
      m.files.push_back({f[0].get<std::string>(), f[1].get<uint64_t>(), f[2].get<uint32_t>()});
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(JsonErrorMessage(path.string(), text, e));
  }
  return m;
}

}  // namespace cadsynth
