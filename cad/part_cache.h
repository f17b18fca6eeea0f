// The part cache: what a run computes per part (imported and tessellated assemblies, convex hulls,
// repeated-shape checks), stored on disk under a key of everything the result depends on, so that
// the next run, and every shard of a farm, reads it instead of computing it again.
//
// Keys are 128-bit XXH3 hashes of the input's bytes (a file's content, a mesh's vertices and
// triangles, the options), of the kind and version of the computation and of a salt naming the
// code that computed it (the pipeline uses the executable's identity), so a changed input, option
// or build never reads an old entry. Values are written under a temporary name and renamed, so
// concurrent shards never see half an entry; each carries its length and checksum, and an entry
// that does not check out is a miss. The cache only saves time: a run with it gives the bytes a
// run without it gives.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cad/core/schema.h"
#include "cad/grasp.h"
#include "cad/hull.h"
#include "cad/mesh.h"
#include "cad/part.h"
#include "cad/symmetry.h"

namespace cadsynth {

// Types stored as their bytes: trivially copyable ones, and fixed-size Eigen vectors and
// matrices (plain arrays of numbers, though Eigen declares copy constructors).
template <typename T>
struct IsPlainBytes : std::is_trivially_copyable<T> {};
template <typename S, int R, int C, int O, int MR, int MC>
struct IsPlainBytes<Eigen::Matrix<S, R, C, O, MR, MC>>
    : std::bool_constant<(R > 0 && C > 0 && std::is_arithmetic_v<S> &&
                          sizeof(Eigen::Matrix<S, R, C, O, MR, MC>) == R * C * sizeof(S))> {};

// A 128-bit content key.
struct CacheKey {
  uint64_t high = 0, low = 0;
  std::string Hex() const;
  bool operator==(const CacheKey& o) const { return high == o.high && low == o.low; }
};

// Builds a key from the bytes of everything a result depends on (XXH3-128, streaming).
class KeyHasher {
 public:
  KeyHasher();
  ~KeyHasher();
  KeyHasher(const KeyHasher&) = delete;
  KeyHasher& operator=(const KeyHasher&) = delete;
  KeyHasher& Bytes(const void* data, size_t size);
  // Text with its length, so that ("ab", "c") and ("a", "bc") differ.
  KeyHasher& Text(std::string_view text);
  template <typename T>
  KeyHasher& Value(const T& value) {
    static_assert(IsPlainBytes<T>::value);
    return Bytes(&value, sizeof(T));
  }
  // A mesh's geometry: positions, normals, triangles and face ids.
  KeyHasher& Geometry(const Mesh& mesh);
  // Every field of a described struct (cad/core/schema.h): its name and exact text.
  template <class Options>
  KeyHasher& Fields(const Options& options) {
    Options::Fields(options, [this](const auto& value, const Field& field) {
      Text(field.Name()).Text(FieldText(value, field));
    });
    return *this;
  }
  CacheKey Key() const;

 private:
  void* state_;
};

// The bytes of a cached value: plain little-endian values and length-prefixed arrays. Reading
// past the end or a length beyond what is left throws Error (a damaged entry is a miss).
class ByteWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(IsPlainBytes<T>::value);
    const size_t at = bytes_.size();
    bytes_.resize(at + sizeof(T));
    std::memcpy(bytes_.data() + at, &value, sizeof(T));
  }
  template <typename T>
  void PutArray(const std::vector<T>& values) {
    static_assert(IsPlainBytes<T>::value);
    Put<uint64_t>(values.size());
    const size_t at = bytes_.size();
    bytes_.resize(at + values.size() * sizeof(T));
    if (!values.empty()) std::memcpy(bytes_.data() + at, values.data(), values.size() * sizeof(T));
  }
  void PutText(std::string_view text);
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(std::string_view bytes) : bytes_(bytes) {}
  template <typename T>
  T Get() {
    static_assert(IsPlainBytes<T>::value);
    T value;
    // IsPlainBytes admits Eigen's fixed-size matrices, whose user-declared copy makes them not
    // trivially copyable to the compiler although their bytes are the whole value.
    std::memcpy(static_cast<void*>(&value), Take(sizeof(T)), sizeof(T));
    return value;
  }
  template <typename T>
  std::vector<T> GetArray() {
    static_assert(IsPlainBytes<T>::value);
    const uint64_t n = Get<uint64_t>();
    if (n > (bytes_.size() - at_) / sizeof(T)) Fail();
    std::vector<T> values(n);
    // (void*: Eigen vectors are plain numbers, though not trivially copyable by declaration)
    if (n > 0) std::memcpy(static_cast<void*>(values.data()), Take(n * sizeof(T)), n * sizeof(T));
    return values;
  }
  std::string GetText();
  bool done() const { return at_ == bytes_.size(); }

 private:
  const char* Take(size_t size);
  [[noreturn]] static void Fail();
  std::string_view bytes_;
  size_t at_ = 0;
};

// What a part cache can hold, as bytes. Decode* throw Error on damaged bytes.
std::string EncodeHull(const ConvexHull& hull);
ConvexHull DecodeHull(std::string_view bytes);
// An object's sampled grasps (parallel-jaw and suction), in the order sampled.
std::string EncodeGrasps(const std::vector<ParallelJawGrasp>& jaw,
                         const std::vector<SuctionGrasp>& suction);
void DecodeGrasps(std::string_view bytes, std::vector<ParallelJawGrasp>* jaw,
                  std::vector<SuctionGrasp>* suction);
// A part's symmetries as detected or measured (DetectSymmetries, MeasureSymmetries, with
// CompareBrepFaces' results if it ran), and the worst deviation of each entry of a recipe's list.
std::string EncodeDetectedSymmetries(const DetectedSymmetries& found,
                                     const std::vector<double>& entry_deviation);
DetectedSymmetries DecodeDetectedSymmetries(std::string_view bytes,
                                            std::vector<double>* entry_deviation);
// An assembly as the importer returns it, B-rep shapes included (OpenCASCADE's binary format),
// and the warnings reading it gave; convex hulls are not stored (they have their own entries).
std::string EncodeAssembly(const Assembly& assembly, const std::vector<std::string>& warnings);
Assembly DecodeAssembly(std::string_view bytes, std::vector<std::string>* warnings);

// The store: one file per entry, dir/<kind>/<first two hex digits>/<key>.
class PartCache {
 public:
  // `salt` names the code whose results are stored (entries of other code are never read).
  PartCache(std::filesystem::path dir, std::string salt);
  PartCache(const PartCache&) = delete;
  PartCache& operator=(const PartCache&) = delete;
  const std::filesystem::path& dir() const { return dir_; }
  // A hasher already holding the salt and `kind` (name and version of the computation).
  void Start(KeyHasher* hasher, std::string_view kind) const;
  // The stored bytes, or nothing when absent, unreadable or damaged.
  std::optional<std::string> Load(std::string_view kind, const CacheKey& key) const;
  // Stores the bytes; a failure (read-only or full file system) warns once per cache and is
  // otherwise ignored: the run goes on without the cache.
  void Store(std::string_view kind, const CacheKey& key, std::string_view bytes) const;

  // Where the cache lives unless told: $CADSYNTH_CACHE when set ("off" disables it), else
  // $XDG_CACHE_HOME/cadsynth, else $HOME/.cache/cadsynth; nothing when disabled or no home.
  static std::optional<std::filesystem::path> DefaultDirectory();

 private:
  std::filesystem::path Path(std::string_view kind, const CacheKey& key) const;
  std::filesystem::path dir_;
  std::string salt_;
  mutable std::atomic<bool> warned_{false};
};

}  // namespace cadsynth
