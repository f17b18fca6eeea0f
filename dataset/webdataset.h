// Webdataset archive shards: a run's (or a farm task's) frames packed into tar archives that a
// training job reads as they are, without a merge, in the convention of BOP's sharded releases
// (bop_toolkit's bop-webdataset: one archive of many samples, each sample's files sharing a key).
//
//   ROOT/webdataset/shard-IIIIII-KKKK.tar   archive K of task I (samples in scene, image order)
//   ROOT/webdataset/shard-IIIIII.json       task I's manifest, written last: the archives, their
//                                           samples, bytes and SHA-256
//
// Sample KEY = SCENEID_IMID (six digits each, BOP's image key). Its members, for each sensor in
// the rig's order (X: the sensor's suffix, "_NAME"; nothing for a single camera):
//
//   KEY.cadsynth{X}.json     the frame's fragment (BOP writer's journal: every file with size and
//                            CRC-32); what merge restores the BOP folders from
//   KEY.camera{X}.json       its scene_camera.json entry (cam_K, depth_scale, cam_R_w2c, ...)
//   KEY.gt{X}.json           its scene_gt.json entries, one per instance
//   KEY.gt_info{X}.json      its scene_gt_info.json entries
//   KEY.rgb{X}.png           then every file the frame wrote, in the fragment's order, named from
//   KEY.depth{X}.png         its path: the scene folder, the scene and image ids dropped, folders
//   KEY.mask{X}_GTID.png     joined with '_' (rgb/IMID.png: rgb.png; mask_visib/IMID_GTID.png:
//   KEY.mask_visib{X}_GTID.png  mask_visib_GTID.png; graspnet/SCENEID/IMID.npy: graspnet.npy)
//   ...
//   KEY.split.txt            "train" or "test", when the split is known while rendering (no
//                            views skipped)
//
// The archive's bytes depend on the frames' files alone (tar headers carry no time or owner), so a
// task run again writes the same archives.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "dataset/bop.h"

namespace cadsynth {

// One view to pack: its scene and image ids, and its split ("train", "test"; empty: unknown).
struct ArchiveSample {
  int scene_id = 0;
  int image_id = 0;
  std::string split;
};

struct ArchiveRecord {
  std::string file;  // name in ROOT/webdataset/
  size_t samples = 0;
  uint64_t bytes = 0;
  std::string sha256;  // hex
  std::string first_key, last_key;
};

struct ArchiveManifest {
  int shard = 0, shards = 1;
  size_t samples = 0;
  std::vector<ArchiveRecord> archives;
};

std::filesystem::path ArchiveFolder(const std::filesystem::path& root);
// ROOT/webdataset/shard-IIIIII.json
std::filesystem::path ManifestPath(const std::filesystem::path& root, int shard);
// The sample key of a view: SCENEID_IMID.
std::string SampleKey(int scene_id, int image_id);

// Packs `samples` (written frames: each sensor's fragment exists under ROOT) into task `shard`'s
// archives, at most options.archive_samples samples and options.archive_megabytes MiB each, then
// writes its manifest. Each file is checked against its fragment (size, CRC-32) first. Throws
// Error naming the file or archive.
ArchiveManifest WriteArchives(const std::filesystem::path& root, const BopOptions& options,
                              const std::vector<BopSensor>& sensors,
                              const std::vector<ArchiveSample>& samples, int shard, int shards);

// Removes the packed frames' files and fragments (a farm task's loose copies, once its archives
// and manifest are complete).
void RemoveArchivedFrames(const std::filesystem::path& root, const BopOptions& options,
                          const std::vector<BopSensor>& sensors,
                          const std::vector<ArchiveSample>& samples);

// The manifests in ROOT/webdataset, by task; throws Error naming a damaged one.
std::vector<ArchiveManifest> ReadArchiveManifests(const std::filesystem::path& root);
ArchiveManifest ReadArchiveManifest(const std::filesystem::path& path);

// Puts the frames of the archives listed by task `shard`'s manifest (every task's: nullopt) back
// into ROOT as BopSceneWriter wrote them (files, then the fragment), except frames whose fragment
// exists. Checks every archive's size and SHA-256 against its manifest and every file against its
// fragment first; throws Error naming the archive or member. Returns the frames restored.
size_t RestoreArchivedFrames(const std::filesystem::path& root, const BopOptions& options,
                             std::optional<int> shard = std::nullopt);

}  // namespace cadsynth
