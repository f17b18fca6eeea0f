// Tar archives as webdataset shards hold them, and SHA-256 as their manifests record it.
//
// TarWriter writes POSIX ustar members whose headers depend on the name and the bytes alone
// (mode 0644, owner 0, time 0, no user names), so the same members give the same archive on any
// machine, at any time, as any user: a retried task's archive equals the first attempt's. Python's
// tarfile, GNU tar and webdataset read them. ReadTar reads such archives back (regular files;
// other member types are skipped).
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

namespace cadsynth {

// SHA-256 (FIPS 180-4) through OpenSSL's libcrypto, fed piece by piece.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void Update(std::string_view bytes);
  // The digest as 64 lowercase hex digits; the object cannot be fed afterwards.
  std::string HexDigest();

 private:
  struct Context;
  std::unique_ptr<Context> context_;
};

// SHA-256 of a whole file, hex; throws Error naming it when it cannot be read.
std::string FileSha256(const std::filesystem::path& path);

// Writes an archive member by member to `path` through a temporary name in the same folder,
// renamed into place by Close() (a reader never sees half an archive). Tracks the archive's size
// and SHA-256 as it goes. Throws Error naming the file on failure.
class TarWriter {
 public:
  explicit TarWriter(std::filesystem::path path);
  ~TarWriter();  // an archive not closed is removed
  TarWriter(const TarWriter&) = delete;
  TarWriter& operator=(const TarWriter&) = delete;

  // Header bytes + data rounded up to 512 of a member of `size` bytes.
  static uint64_t MemberBytes(uint64_t size) { return 512 + (size + 511) / 512 * 512; }
  static constexpr uint64_t kEndBytes = 1024;  // the two zero blocks that end an archive

  // `name`: at most 100 bytes, no '/' at either end, no "..".
  void Add(std::string_view name, std::string_view bytes);
  // Ends the archive and renames it into place.
  void Close();
  uint64_t bytes() const { return bytes_; }
  std::string HexDigest() { return sha_.HexDigest(); }  // after Close()

 private:
  void Put(std::string_view bytes);
  std::filesystem::path path_, temporary_;
  std::ofstream out_;
  Sha256 sha_;
  uint64_t bytes_ = 0;
  bool closed_ = false;
};

// The ustar header block of a regular file member (exposed for tests).
std::string TarHeader(std::string_view name, uint64_t size);

// Calls `member(name, bytes)` for each regular file of the archive at `path`, in order; stops
// early when it returns false. Throws Error naming the file on a damaged or truncated archive.
void ReadTar(const std::filesystem::path& path,
             const std::function<bool(const std::string& name, std::string&& bytes)>& member);

}  // namespace cadsynth
