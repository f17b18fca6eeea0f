#include "dataset/webdataset.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <system_error>

#include <tbb/parallel_for.h>

#include "cad/core/error.h"
#include "dataset/bop_fragment.h"
#include "dataset/bop_internal.h"
#include "dataset/bop_read.h"
#include "dataset/file_io.h"
#include "dataset/tar_archive.h"

namespace cadsynth {

using bop_internal::Fragment;
using bop_internal::Json;

std::filesystem::path ArchiveFolder(const std::filesystem::path& root) {
  return root / "webdataset";
}

namespace {

std::string Id(int id, int digits) {
  char text[32];
  std::snprintf(text, sizeof(text), "%0*d", digits, id);
  return text;
}

std::string ArchiveName(int shard, size_t k) {
  return "shard-" + Id(shard, 6) + "-" + Id(static_cast<int>(k), 4) + ".tar";
}

std::filesystem::path FragmentPath(const std::filesystem::path& root, const BopOptions& options,
                                   int scene_id, int image_id, const std::string& suffix) {
  return root / options.split / Id6(scene_id) / (".fragments" + suffix) / (Id6(image_id) + ".json");
}

// The member name (after "KEY.") of a frame's file `path` (relative to ROOT): the scene folder,
// the scene id and the image id dropped, folders joined with '_'. Null when the path does not
// follow that pattern (the caller numbers the file instead).
std::optional<std::string> FileMemberName(const std::string& path, const BopOptions& options,
                                          int scene_id, int image_id) {
  std::string rest = path;
  const std::string scene_folder = options.split + "/" + Id6(scene_id) + "/";
  if (rest.rfind(scene_folder, 0) == 0) rest = rest.substr(scene_folder.size());
  std::vector<std::string> parts;
  for (size_t start = 0; start <= rest.size();) {
    const size_t slash = std::min(rest.find('/', start), rest.size());
    parts.push_back(rest.substr(start, slash - start));
    start = slash + 1;
  }
  std::string file = parts.back();
  parts.pop_back();
  const std::string im = Id6(image_id);
  if (file.rfind(im, 0) != 0) return std::nullopt;
  file = file.substr(im.size());  // "_000001.png", ".png", "_labels.npy"
  std::string name;
  for (const std::string& part : parts) {
    if (part == Id6(scene_id) || part.empty()) continue;
    name += (name.empty() ? "" : "_") + part;
  }
  name += file;
  if (name.empty() || name[0] == '.' || name[0] == '_' || name.find('.') == std::string::npos)
    return std::nullopt;
  return name;
}

// The member names of a fragment's files, in its order: FileMemberName, or "fileN.EXT" where it
// has none or would repeat a name already taken in the sample.
std::vector<std::string> FileMemberNames(const Fragment& fragment, const BopOptions& options,
                                         int scene_id, int image_id, std::set<std::string>* taken) {
  std::vector<std::string> names;
  for (size_t i = 0; i < fragment.files.size(); ++i) {
    const std::string& path = fragment.files[i].path;
    std::optional<std::string> name = FileMemberName(path, options, scene_id, image_id);
    if (!name || taken->count(*name)) {
      const std::string ext = std::filesystem::path(path).extension().string();
      name = "file" + std::to_string(i) + (ext.empty() ? ".bin" : ext);
    }
    taken->insert(*name);
    names.push_back(*name);
  }
  return names;
}

// A sample's members, in archive order.
struct Member {
  std::string name;
  std::string bytes;
};

std::vector<Member> SampleMembers(const std::filesystem::path& root, const BopOptions& options,
                                  const std::vector<BopSensor>& sensors,
                                  const ArchiveSample& sample) {
  const std::string key = SampleKey(sample.scene_id, sample.image_id);
  std::vector<Member> members;
  std::set<std::string> taken;
  for (const BopSensor& sensor : sensors) {
    const std::string x = sensor.Suffix();
    const std::filesystem::path fragment_path =
        FragmentPath(root, options, sample.scene_id, sample.image_id, x);
    std::string text = ReadFileText(fragment_path);
    const Fragment fragment = bop_internal::ParseFragmentText(text, fragment_path.string());
    for (const std::string name : {"cadsynth", "camera", "gt", "gt_info"})
      taken.insert(name + x + ".json");
    members.push_back({key + ".cadsynth" + x + ".json", std::move(text)});
    members.push_back({key + ".camera" + x + ".json", fragment.camera.dump()});
    members.push_back({key + ".gt" + x + ".json", fragment.gt.dump()});
    members.push_back({key + ".gt_info" + x + ".json", fragment.gt_info.dump()});
    const std::vector<std::string> names =
        FileMemberNames(fragment, options, sample.scene_id, sample.image_id, &taken);
    for (size_t i = 0; i < fragment.files.size(); ++i) {
      const FileRecord& record = fragment.files[i];
      std::string bytes;
      try {
        bytes = ReadFileText(root / record.path);
      } catch (const Error&) {
        bytes.clear();
      }
      if (bytes.size() != record.size || Crc32(bytes) != record.crc32)
        throw Error((root / record.path).string() +
                    ": missing, or its size or CRC-32 differs from the frame's manifest (cannot " +
                    "archive image " + std::to_string(sample.image_id) + " of scene " +
                    std::to_string(sample.scene_id) + ")");
      members.push_back({key + "." + names[i], std::move(bytes)});
    }
  }
  if (!sample.split.empty()) members.push_back({key + ".split.txt", sample.split});
  return members;
}

Json ManifestJson(const ArchiveManifest& manifest) {
  Json archives = Json::array();
  for (const ArchiveRecord& a : manifest.archives) {
    archives.push_back({{"file", a.file},
                        {"samples", a.samples},
                        {"bytes", a.bytes},
                        {"sha256", a.sha256},
                        {"first_key", a.first_key},
                        {"last_key", a.last_key}});
  }
  return Json{{"format", "cadsynth-webdataset 1"},
              {"shard", manifest.shard},
              {"shards", manifest.shards},
              {"samples", manifest.samples},
              {"archives", archives}};
}

}  // namespace

std::filesystem::path ManifestPath(const std::filesystem::path& root, int shard) {
  return ArchiveFolder(root) / ("shard-" + Id(shard, 6) + ".json");
}

std::string SampleKey(int scene_id, int image_id) { return Id6(scene_id) + "_" + Id6(image_id); }

ArchiveManifest WriteArchives(const std::filesystem::path& root, const BopOptions& options,
                              const std::vector<BopSensor>& sensors,
                              const std::vector<ArchiveSample>& samples, int shard, int shards) {
  const std::filesystem::path folder = ArchiveFolder(root);
  CreateFolder(folder);
  // A manifest of an earlier attempt goes first: until the new one is written, the task's
  // archives are not complete.
  std::error_code ec;
  std::filesystem::remove(ManifestPath(root, shard), ec);
  ArchiveManifest manifest;
  manifest.shard = shard;
  manifest.shards = shards;
  const uint64_t max_bytes = static_cast<uint64_t>(options.archive_megabytes) << 20;
  std::unique_ptr<TarWriter> tar;
  ArchiveRecord record;
  const auto close = [&] {
    if (!tar) return;
    tar->Close();
    record.bytes = tar->bytes();
    record.sha256 = tar->HexDigest();
    manifest.archives.push_back(record);
    tar.reset();
  };
  // Samples' members read (and checked) in parallel, a batch at a time; written in order.
  constexpr size_t kBatch = 32;
  std::vector<std::vector<Member>> batch;
  for (size_t first = 0; first < samples.size(); first += kBatch) {
    const size_t count = std::min(kBatch, samples.size() - first);
    batch.assign(count, {});
    tbb::parallel_for(size_t{0}, count, [&](size_t k) {
      batch[k] = SampleMembers(root, options, sensors, samples[first + k]);
    });
    for (size_t k = 0; k < count; ++k) {
      const ArchiveSample& sample = samples[first + k];
      const std::vector<Member>& members = batch[k];
      uint64_t sample_bytes = 0;
      for (const Member& m : members) sample_bytes += TarWriter::MemberBytes(m.bytes.size());
      if (tar && (record.samples >= static_cast<size_t>(options.archive_samples) ||
                  tar->bytes() + sample_bytes + TarWriter::kEndBytes > max_bytes)) {
        close();
      }
      if (!tar) {
        record = ArchiveRecord{};
        record.file = ArchiveName(shard, manifest.archives.size());
        record.first_key = SampleKey(sample.scene_id, sample.image_id);
        tar = std::make_unique<TarWriter>(folder / record.file);
      }
      for (const Member& m : members) tar->Add(m.name, m.bytes);
      ++record.samples;
      ++manifest.samples;
      record.last_key = SampleKey(sample.scene_id, sample.image_id);
    }
  }
  close();
  WriteFileAtomic(ManifestPath(root, shard), ManifestJson(manifest).dump(1) + "\n");
  return manifest;
}

void RemoveArchivedFrames(const std::filesystem::path& root, const BopOptions& options,
                          const std::vector<BopSensor>& sensors,
                          const std::vector<ArchiveSample>& samples) {
  for (const ArchiveSample& sample : samples) {
    for (const BopSensor& sensor : sensors) {
      const std::filesystem::path fragment_path =
          FragmentPath(root, options, sample.scene_id, sample.image_id, sensor.Suffix());
      const Fragment fragment = bop_internal::ReadFragment(fragment_path);
      std::error_code ec;
      // The fragment first: a frame without it counts as not written, whatever files remain.
      std::filesystem::remove(fragment_path, ec);
      if (ec) throw Error(fragment_path.string() + ": cannot remove: " + ec.message());
      for (const FileRecord& record : fragment.files)
        std::filesystem::remove(root / record.path, ec);
    }
  }
}

ArchiveManifest ReadArchiveManifest(const std::filesystem::path& path) {
  Json j;
  try {
    j = Json::parse(ReadFileText(path));
  } catch (const Json::exception& e) {
    throw Error(path.string() + ": not valid JSON: " + e.what());
  }
  ArchiveManifest m;
  try {
    if (j.at("format") != "cadsynth-webdataset 1")
      throw Error(path.string() + ": not a cadsynth webdataset manifest");
    m.shard = j.at("shard").get<int>();
    m.shards = j.at("shards").get<int>();
    m.samples = j.at("samples").get<size_t>();
    for (const Json& a : j.at("archives")) {
      ArchiveRecord r;
      r.file = a.at("file").get<std::string>();
      r.samples = a.at("samples").get<size_t>();
      r.bytes = a.at("bytes").get<uint64_t>();
      r.sha256 = a.at("sha256").get<std::string>();
      r.first_key = a.at("first_key").get<std::string>();
      r.last_key = a.at("last_key").get<std::string>();
      if (r.file.find('/') != std::string::npos || r.file.find("..") != std::string::npos)
        throw Error(path.string() + ": archive name '" + r.file + "' leaves the folder");
      m.archives.push_back(std::move(r));
    }
  } catch (const Json::exception& e) {
    throw Error(path.string() + ": " + e.what());
  }
  return m;
}

std::vector<ArchiveManifest> ReadArchiveManifests(const std::filesystem::path& root) {
  std::vector<std::filesystem::path> paths;
  if (!std::filesystem::is_directory(ArchiveFolder(root))) return {};
  for (const auto& entry : std::filesystem::directory_iterator(ArchiveFolder(root))) {
    const std::string name = entry.path().filename().string();
    if (name.size() == 17 && name.rfind("shard-", 0) == 0 && name.substr(12) == ".json")
      paths.push_back(entry.path());
  }
  std::sort(paths.begin(), paths.end());
  std::vector<ArchiveManifest> manifests;
  for (const auto& path : paths) manifests.push_back(ReadArchiveManifest(path));
  return manifests;
}

namespace {

// The sensor suffix X of a fragment member "cadsynth{X}.json"; null for another member.
std::optional<std::string> FragmentSuffix(const std::string& name) {
  if (name.rfind("cadsynth", 0) != 0 || name.size() < 13 || name.substr(name.size() - 5) != ".json")
    return std::nullopt;
  return name.substr(8, name.size() - 13);
}

// Writes one sample's frames (each sensor's files, then its fragment) unless already there.
// `members` in archive order (names after "KEY.").
size_t RestoreSample(const std::filesystem::path& root, const BopOptions& options,
                     const std::string& archive, const std::string& key,
                     const std::vector<Member>& members) {
  const auto scene = ParseBopId(key.substr(0, 6));
  const auto image = key.size() == 13 && key[6] == '_' ? ParseBopId(key.substr(7)) : std::nullopt;
  if (!scene || !image) throw Error(archive + ": sample key '" + key + "' is not SCENEID_IMID");
  std::map<std::string, const std::string*> by_name;
  for (const Member& m : members) by_name[m.name] = &m.bytes;
  size_t restored = 0;
  std::set<std::string> taken;  // as SampleMembers takes them: sensor by sensor
  for (const Member& member : members) {
    const std::optional<std::string> x = FragmentSuffix(member.name);
    if (!x) continue;
    if (!x->empty() && ((*x)[0] != '_' || x->find_first_of("/.") != std::string::npos))
      throw Error(archive + ": member '" + key + "." + member.name + "' names no sensor");
    const std::string origin = archive + ":" + key + "." + member.name;
    const Fragment fragment = bop_internal::ParseFragmentText(member.bytes, origin);
    for (const std::string n : {"cadsynth", "camera", "gt", "gt_info"})
      taken.insert(n + *x + ".json");
    const std::vector<std::string> names =
        FileMemberNames(fragment, options, *scene, *image, &taken);
    const std::filesystem::path fragment_path = FragmentPath(root, options, *scene, *image, *x);
    if (std::filesystem::exists(fragment_path)) continue;
    for (size_t i = 0; i < fragment.files.size(); ++i) {
      const FileRecord& record = fragment.files[i];
      const auto it = by_name.find(names[i]);
      if (it == by_name.end())
        throw Error(archive + ": sample " + key + " lacks member '" + names[i] + "' (" +
                    record.path + ")");
      const std::string& bytes = *it->second;
      if (bytes.size() != record.size || Crc32(bytes) != record.crc32)
        throw Error(archive + ": member '" + key + "." + names[i] +
                    "' differs from its manifest entry (size or CRC-32)");
      const std::filesystem::path path = root / record.path;
      CreateFolder(path.parent_path());
      WriteFileAtomic(path, bytes);
    }
    CreateFolder(fragment_path.parent_path());
    WriteFileAtomic(fragment_path, member.bytes);
    ++restored;
  }
  return restored;
}

}  // namespace

size_t RestoreArchivedFrames(const std::filesystem::path& root, const BopOptions& options,
                             std::optional<int> shard) {
  size_t restored = 0;
  for (const ArchiveManifest& manifest : ReadArchiveManifests(root)) {
    if (shard && manifest.shard != *shard) continue;
    for (const ArchiveRecord& record : manifest.archives) {
      const std::filesystem::path path = ArchiveFolder(root) / record.file;
      std::error_code ec;
      const uint64_t size = std::filesystem::file_size(path, ec);
      if (ec) throw Error(path.string() + ": listed by its manifest but missing");
      if (size != record.bytes || FileSha256(path) != record.sha256)
        throw Error(path.string() + ": damaged (its size or SHA-256 differs from " +
                    ManifestPath(root, manifest.shard).filename().string() + ")");
      std::string key;
      std::vector<Member> members;
      const auto flush = [&] {
        if (!key.empty()) restored += RestoreSample(root, options, path.string(), key, members);
        members.clear();
      };
      ReadTar(path, [&](const std::string& name, std::string&& bytes) {
        const size_t dot = name.find('.');
        if (dot == std::string::npos)
          throw Error(path.string() + ": member '" + name + "' has no key");
        if (name.compare(0, dot, key) != 0) {
          flush();
          key = name.substr(0, dot);
        }
        members.push_back({name.substr(dot + 1), std::move(bytes)});
        return true;
      });
      flush();
    }
  }
  return restored;
}

}  // namespace cadsynth
