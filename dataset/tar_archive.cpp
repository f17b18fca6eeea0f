#include "dataset/tar_archive.h"

#include <openssl/evp.h>

#include <array>
#include <cstring>
#include <system_error>

#include "cad/core/error.h"

namespace cadsynth {

struct Sha256::Context {
  EVP_MD_CTX* ctx = nullptr;
};

Sha256::Sha256() : context_(std::make_unique<Context>()) {
  context_->ctx = EVP_MD_CTX_new();
  if (context_->ctx == nullptr || EVP_DigestInit_ex(context_->ctx, EVP_sha256(), nullptr) != 1)
    throw Error("SHA-256: OpenSSL could not start a digest");
}

Sha256::~Sha256() { EVP_MD_CTX_free(context_->ctx); }

void Sha256::Update(std::string_view bytes) {
  if (EVP_DigestUpdate(context_->ctx, bytes.data(), bytes.size()) != 1)
    throw Error("SHA-256: OpenSSL could not digest");
}

std::string Sha256::HexDigest() {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(context_->ctx, digest.data(), &length) != 1 || length != 32)
    throw Error("SHA-256: OpenSSL could not finish a digest");
  static const char* hex = "0123456789abcdef";
  std::string text;
  for (unsigned int i = 0; i < length; ++i) {
    text += hex[digest[i] >> 4];
    text += hex[digest[i] & 15];
  }
  return text;
}

std::string FileSha256(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open");
  Sha256 sha;
  std::string buffer(1 << 20, '\0');
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    sha.Update(std::string_view(buffer.data(), static_cast<size_t>(in.gcount())));
  }
  if (in.bad()) throw Error(path.string() + ": read error");
  return sha.HexDigest();
}

namespace {

// `value` as `width - 1` octal digits and a NUL, as ustar's numeric fields hold it.
void PutOctal(char* field, size_t width, uint64_t value) {
  for (size_t i = width - 1; i-- > 0;) {
    field[i] = static_cast<char>('0' + (value & 7));
    value >>= 3;
  }
  field[width - 1] = '\0';
}

uint64_t HeaderSum(const char* block) {
  uint64_t sum = 0;
  for (int i = 0; i < 512; ++i) {
    // The checksum field counts as eight spaces.
    sum += (i >= 148 && i < 156) ? uint64_t{' '} : static_cast<unsigned char>(block[i]);
  }
  return sum;
}

}  // namespace

std::string TarHeader(std::string_view name, uint64_t size) {
  if (name.empty() || name.size() > 100 || name.front() == '/' || name.back() == '/' ||
      name.find("..") != std::string_view::npos || name.find('\0') != std::string_view::npos)
    throw Error("tar: member name '" + std::string(name) + "' is empty, too long or not plain");
  if (size >= (uint64_t{1} << 33)) throw Error("tar: member '" + std::string(name) + "' >= 8 GiB");
  std::string block(512, '\0');
  std::memcpy(block.data(), name.data(), name.size());
  PutOctal(&block[100], 8, 0644);  // mode
  PutOctal(&block[108], 8, 0);     // uid
  PutOctal(&block[116], 8, 0);     // gid
  PutOctal(&block[124], 12, size);
  PutOctal(&block[136], 12, 0);  // mtime
  block[156] = '0';              // a regular file
  std::memcpy(&block[257], "ustar", 6);
  std::memcpy(&block[263], "00", 2);
  PutOctal(&block[148], 7, HeaderSum(block.data()));
  block[155] = ' ';
  return block;
}

TarWriter::TarWriter(std::filesystem::path path)
    : path_(std::move(path)), temporary_(path_.string() + ".part") {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) throw Error(temporary_.string() + ": cannot create");
}

TarWriter::~TarWriter() {
  if (closed_) return;
  out_.close();
  std::error_code ec;
  std::filesystem::remove(temporary_, ec);
}

void TarWriter::Put(std::string_view bytes) {
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out_) throw Error(temporary_.string() + ": write failed (disk full?)");
  sha_.Update(bytes);
  bytes_ += bytes.size();
}

void TarWriter::Add(std::string_view name, std::string_view bytes) {
  Put(TarHeader(name, bytes.size()));
  Put(bytes);
  static const char zeros[512] = {};
  if (bytes.size() % 512 != 0) Put(std::string_view(zeros, 512 - bytes.size() % 512));
}

void TarWriter::Close() {
  static const char zeros[kEndBytes] = {};
  Put(std::string_view(zeros, kEndBytes));
  out_.close();
  if (!out_) throw Error(temporary_.string() + ": write failed (disk full?)");
  std::error_code ec;
  std::filesystem::rename(temporary_, path_, ec);
  if (ec) throw Error(path_.string() + ": cannot rename into place: " + ec.message());
  closed_ = true;
}

void ReadTar(const std::filesystem::path& path,
             const std::function<bool(const std::string& name, std::string&& bytes)>& member) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open");
  const auto fail = [&](uint64_t offset, const std::string& what) {
    throw Error(path.string() + ": byte " + std::to_string(offset) + ": " + what);
  };
  uint64_t offset = 0;
  char block[512];
  while (true) {
    in.read(block, 512);
    if (in.gcount() != 512) fail(offset, "truncated (no end-of-archive blocks)");
    bool zero = true;
    for (char c : block) zero = zero && c == '\0';
    if (zero) return;
    uint64_t stored = 0, size = 0;
    for (int i = 148; i < 156 && block[i] >= '0' && block[i] <= '7'; ++i)
      stored = stored * 8 + static_cast<uint64_t>(block[i] - '0');
    if (stored != HeaderSum(block)) fail(offset, "header checksum differs");
    for (int i = 124; i < 136 && block[i] >= '0' && block[i] <= '7'; ++i)
      size = size * 8 + static_cast<uint64_t>(block[i] - '0');
    std::string name(block, strnlen(block, 100));
    if (std::memcmp(&block[257], "ustar", 5) == 0 && block[345] != '\0')
      name = std::string(&block[345], strnlen(&block[345], 155)) + "/" + name;
    std::string bytes(size, '\0');
    in.read(bytes.data(), static_cast<std::streamsize>(size));
    if (static_cast<uint64_t>(in.gcount()) != size) fail(offset, "member '" + name + "' truncated");
    in.ignore(static_cast<std::streamsize>((512 - size % 512) % 512));
    offset += TarWriter::MemberBytes(size);
    const char type = block[156];
    if ((type == '0' || type == '\0') && !member(name, std::move(bytes))) return;
  }
}

}  // namespace cadsynth
