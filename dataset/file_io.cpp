#include "dataset/file_io.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "cad/error.h"

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

}  // namespace cadsynth
