#include "dataset/file_io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

#include <zlib.h>

#include "cad/core/error.h"

namespace cadsynth {

void WriteFileAtomic(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (file == nullptr) {
    throw Error(path.string() + ": cannot create file: " + std::strerror(errno));
  }
  const size_t written = std::fwrite(bytes.data(), 1, bytes.size(), file);
  const int write_errno = errno;
  const bool closed = std::fclose(file) == 0;
  if (written != bytes.size() || !closed) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    throw Error(path.string() + ": cannot write file: " +
                std::strerror(written != bytes.size() ? write_errno : errno));
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw Error(path.string() + ": cannot move file into place: " + ec.message());
  }
}

void CreateFolder(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw Error(dir.string() + ": cannot create folder: " + ec.message());
}

void LinkOrCopy(const std::filesystem::path& from, const std::filesystem::path& to) {
  std::error_code ec;
  std::filesystem::remove(to, ec);
  std::filesystem::create_hard_link(from, to, ec);
  if (!ec) return;
  std::filesystem::copy_file(from, to, std::filesystem::copy_options::overwrite_existing, ec);
  if (ec) throw Error(to.string() + ": cannot link or copy " + from.string() + ": " + ec.message());
}

uint32_t Crc32(std::string_view bytes, uint32_t crc) {
  // zlib takes lengths as uInt: feed large buffers in pieces.
  uLong value = crc;
  while (!bytes.empty()) {
    const size_t n = std::min<size_t>(bytes.size(), 1u << 30);
    value = ::crc32(value, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(n));
    bytes.remove_prefix(n);
  }
  return static_cast<uint32_t>(value);
}

std::string CheckFile(const std::filesystem::path& root, const FileRecord& record) {
  const std::filesystem::path path = root / record.path;
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) return "missing";
  if (size != record.size) {
    return std::to_string(size) + " bytes, the manifest says " + std::to_string(record.size);
  }
  std::string text;
  try {
    text = ReadFileText(path);
  } catch (const Error&) {
    return "unreadable";
  }
  return Crc32(text) == record.crc32 ? std::string() : "checksum differs from the manifest";
}

std::string FileLog::Relative(const std::filesystem::path& path) const {
  return path.lexically_relative(root_).generic_string();
}

void FileLog::Write(const std::filesystem::path& path, std::string_view bytes) {
  WriteFileAtomic(path, bytes);
  records_.push_back({Relative(path), bytes.size(), Crc32(bytes)});
}

void FileLog::Link(const std::filesystem::path& from, const std::filesystem::path& to) {
  LinkOrCopy(from, to);
  const std::string source = Relative(from);
  for (const FileRecord& r : records_) {
    if (r.path == source) {
      records_.push_back({Relative(to), r.size, r.crc32});
      return;
    }
  }
  Add(to);
}

void FileLog::Add(const std::filesystem::path& path) {
  const std::string text = ReadFileText(path);
  records_.push_back({Relative(path), text.size(), Crc32(text)});
}

std::string Id6(int id) {
  char buffer[16];
  std::snprintf(buffer, sizeof(buffer), "%06d", id);
  return buffer;
}

std::string ReadFileText(const std::filesystem::path& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw Error(path.string() + ": cannot open: " + std::strerror(errno));
  std::string text;
  char buffer[65536];
  for (size_t n; (n = std::fread(buffer, 1, sizeof(buffer), file)) > 0;) text.append(buffer, n);
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) throw Error(path.string() + ": cannot read");
  return text;
}

}  // namespace cadsynth
