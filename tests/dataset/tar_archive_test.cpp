// Tar members and SHA-256 against answers worked out independently: FIPS 180-4's test vectors,
// the ustar header fields as POSIX lays them out, a checksum summed here byte by byte.
#include "dataset/tar_archive.h"

#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

using testing::ReadFile;
using testing::ScratchDir;

TEST(Sha256, MatchesTheStandardsTestVectors) {
  Sha256 empty;
  EXPECT_EQ(empty.HexDigest(), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  Sha256 abc;
  abc.Update("a");
  abc.Update("bc");  // fed in pieces
  EXPECT_EQ(abc.HexDigest(), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  Sha256 two_blocks;
  two_blocks.Update("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq");
  EXPECT_EQ(two_blocks.HexDigest(),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");  // FIPS 180-2 B.2
}

TEST(Tar, HeaderFieldsAreUstarsWithNoTimeOrOwner) {
  const std::string h = TarHeader("000000_000001.rgb.png", 1234);
  ASSERT_EQ(h.size(), 512u);
  EXPECT_EQ(h.substr(0, 21), "000000_000001.rgb.png");
  EXPECT_EQ(h[21], '\0');
  EXPECT_EQ(h.substr(100, 8), std::string("0000644\0", 8));
  EXPECT_EQ(h.substr(108, 8), std::string("0000000\0", 8));        // uid
  EXPECT_EQ(h.substr(124, 12), std::string("00000002322\0", 12));  // 1234 = 0o2322
  EXPECT_EQ(h.substr(136, 12), std::string("00000000000\0", 12));  // mtime 0
  EXPECT_EQ(h[156], '0');
  EXPECT_EQ(h.substr(257, 8), std::string("ustar\0"
                                          "00",
                                          8));
  // The checksum: every byte summed with the checksum field as eight spaces, six octal digits,
  // NUL, space.
  unsigned sum = 0;
  for (int i = 0; i < 512; ++i)
    sum += (i >= 148 && i < 156) ? 32u : static_cast<unsigned char>(h[i]);
  char expected[8];
  std::snprintf(expected, sizeof(expected), "%06o", sum);
  EXPECT_EQ(h.substr(148, 6), expected);
  EXPECT_EQ(h[154], '\0');
  EXPECT_EQ(h[155], ' ');
  EXPECT_THROW(TarHeader(std::string(101, 'a'), 1), Error);
  EXPECT_THROW(TarHeader("../x", 1), Error);
  EXPECT_THROW(TarHeader("/x", 1), Error);
}

TEST(Tar, WritesAndReadsBackWithSizeAndDigestOfTheFile) {
  ScratchDir dir;
  const std::vector<std::pair<std::string, std::string>> members = {
      {"a.txt", "abc"},
      {"b.bin", std::string(512, 'x')},
      {"c.json", ""},
      {"d", std::string(513, 'y')}};
  {
    TarWriter tar(dir / "t.tar");
    for (const auto& [name, bytes] : members) tar.Add(name, bytes);
    EXPECT_FALSE(std::filesystem::exists(dir / "t.tar"));  // only once closed
    tar.Close();
    // Headers, data rounded up to 512, two zero blocks: 4 * 512 + 512 + 512 + 0 + 1024 + 1024.
    EXPECT_EQ(tar.bytes(), 5120u);
    EXPECT_EQ(std::filesystem::file_size(dir / "t.tar"), 5120u);
    EXPECT_EQ(tar.HexDigest(), FileSha256(dir / "t.tar"));
  }
  std::vector<std::pair<std::string, std::string>> read;
  ReadTar(dir / "t.tar", [&](const std::string& name, std::string&& bytes) {
    read.emplace_back(name, std::move(bytes));
    return true;
  });
  EXPECT_EQ(read, members);
  // Truncated: named as such.
  const std::string bytes = ReadFile(dir / "t.tar");
  std::ofstream(dir / "cut.tar", std::ios::binary) << bytes.substr(0, 1500);
  EXPECT_THROW(ReadTar(dir / "cut.tar", [](const std::string&, std::string&&) { return true; }),
               Error);
  // A flipped header byte breaks its checksum.
  std::string bad = bytes;
  bad[3] ^= 4;
  std::ofstream(dir / "bad.tar", std::ios::binary) << bad;
  try {
    ReadTar(dir / "bad.tar", [](const std::string&, std::string&&) { return true; });
    ADD_FAILURE();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("byte 0: header checksum differs"), std::string::npos);
  }
}

TEST(Tar, AnArchiveNotClosedLeavesNothing) {
  ScratchDir dir;
  {
    TarWriter tar(dir / "t.tar");
    tar.Add("a.txt", "abc");
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace cadsynth
