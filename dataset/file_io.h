// Writing files so that no reader ever sees half of one.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace cadsynth {

// Writes `bytes` to `path` through a temporary name in the same folder, then renames it into
// place. Throws Error naming the file (with the system's reason, e.g. a full disk) on failure.
void WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes);

// Creates `dir` and its parents; throws Error naming it on failure.
void CreateFolder(const std::filesystem::path& dir);

// Makes `to` a hard link to `from` (no extra disk space), or a copy where links are not possible
// (another file system); replaces an existing `to`. Throws Error naming the files on failure.
void LinkOrCopy(const std::filesystem::path& from, const std::filesystem::path& to);

// The whole file; throws Error naming it when it cannot be read.
std::string ReadFileText(const std::filesystem::path& path);

// CRC-32 (zlib's, as Python's zlib.crc32 and `crc32` compute it) of `bytes`, continuing `crc`.
uint32_t Crc32(std::string_view bytes, uint32_t crc = 0);

// One written file as the manifest records it: path relative to the dataset root, size, CRC-32.
struct FileRecord {
  std::string path;
  uint64_t size = 0;
  uint32_t crc32 = 0;
};

// Empty when ROOT/record.path exists with the recorded size and checksum; otherwise what differs
// ("missing", "12 bytes, the manifest says 40", "checksum differs").
std::string CheckFile(const std::filesystem::path& root, const FileRecord& record);

// Writes files under `root` and records each one (size, CRC-32 of the bytes written): the files
// one frame wrote, so that a resumed run or a merge can tell a complete frame from a damaged one.
// Not thread-safe: one log per frame.
class FileLog {
 public:
  explicit FileLog(std::filesystem::path root) : root_(std::move(root)) {}
  // WriteFileAtomic, recorded.
  void Write(const std::filesystem::path& path, std::string_view bytes);
  // LinkOrCopy, recorded with the checksum of `from` (read back unless this log wrote it).
  void Link(const std::filesystem::path& from, const std::filesystem::path& to);
  // A file written by other means (a library): read back and recorded.
  void Add(const std::filesystem::path& path);
  const std::vector<FileRecord>& records() const { return records_; }

 private:
  std::string Relative(const std::filesystem::path& path) const;
  std::filesystem::path root_;
  std::vector<FileRecord> records_;
};

// A BOP id: six digits, zero-padded ("000042").
std::string Id6(int id);

}  // namespace cadsynth
