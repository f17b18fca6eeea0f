#include "dataset/acronym.h"

#include <hdf5.h>

#include <algorithm>
#include <cstdint>
#include <memory>

#include "cad/core/error.h"

namespace cadsynth {

namespace {

// An HDF5 handle closed by its own function when it goes out of scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

class Writer {
 public:
  explicit Writer(const std::filesystem::path& path) : path_(path) {
    file_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file_ < 0) Fail("cannot create the file");
    links_ = H5Pcreate(H5P_LINK_CREATE);
    // No modification times in object headers (HDF5 records them by default): the same grasps
    // give the same bytes.
    datasets_ = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_obj_track_times(datasets_, 0);
    groups_ = H5Pcreate(H5P_GROUP_CREATE);
    H5Pset_obj_track_times(groups_, 0);
  }
  ~Writer() {
    if (groups_ >= 0) H5Pclose(groups_);
    if (datasets_ >= 0) H5Pclose(datasets_);
    if (links_ >= 0) H5Pclose(links_);
    if (file_ >= 0) H5Fclose(file_);
  }
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  void Doubles(const std::string& name, const std::vector<hsize_t>& dims, const double* data) {
    Write(name, dims, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, data);
  }
  void Int64s(const std::string& name, const std::vector<hsize_t>& dims, const int64_t* data) {
    Write(name, dims, H5T_NATIVE_INT64, H5T_STD_I64LE, data);
  }
  void Scalar(const std::string& name, double value) { Doubles(name, {}, &value); }
  void Group(const std::string& name) {
    const Handle group(H5Gcreate2(file_, name.c_str(), links_, groups_, H5P_DEFAULT), H5Gclose);
    if (!group.ok()) Fail("cannot create group " + name);
  }
  // A scalar variable-length string (what h5py writes for a Python str).
  void Text(const std::string& name, const std::string& value) {
    const Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(type.get(), H5T_VARIABLE);
    H5Tset_cset(type.get(), H5T_CSET_UTF8);
    const Handle space(H5Screate(H5S_SCALAR), H5Sclose);
    const Handle set(
        H5Dcreate2(file_, name.c_str(), type.get(), space.get(), links_, datasets_, H5P_DEFAULT),
        H5Dclose);
    const char* text = value.c_str();
    if (!set.ok() || H5Dwrite(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &text) < 0)
      Fail("cannot write " + name);
  }
  void Close() {
    if (H5Fclose(file_) < 0) Fail("cannot finish the file");
    file_ = -1;
  }

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    throw Error(path_.string() + ": " + what);
  }
  void Write(const std::string& name, const std::vector<hsize_t>& dims, hid_t memory, hid_t stored,
             const void* data) {
    const Handle space(dims.empty()
                           ? H5Screate(H5S_SCALAR)
                           : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr),
                       H5Sclose);
    const Handle set(
        H5Dcreate2(file_, name.c_str(), stored, space.get(), links_, datasets_, H5P_DEFAULT),
        H5Dclose);
    if (!set.ok() || H5Dwrite(set.get(), memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
      Fail("cannot write " + name);
  }

  std::filesystem::path path_;
  hid_t file_ = -1, links_ = -1, datasets_ = -1, groups_ = -1;
};

// The number of elements of dataset `name` and its values as doubles (or int64s).
template <typename T>
std::vector<T> ReadAll(hid_t file, const std::string& name, hid_t memory,
                       const std::filesystem::path& path) {
  const Handle set(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.ok()) throw Error(path.string() + ": no dataset " + name);
  const Handle space(H5Dget_space(set.get()), H5Sclose);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  std::vector<T> out(static_cast<size_t>(std::max<hssize_t>(n, 0)));
  if (n > 0 && H5Dread(set.get(), memory, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    throw Error(path.string() + ": cannot read " + name);
  return out;
}

std::string ReadText(hid_t file, const std::string& name, const std::filesystem::path& path) {
  const Handle set(H5Dopen2(file, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!set.ok()) throw Error(path.string() + ": no dataset " + name);
  const Handle type(H5Dget_type(set.get()), H5Tclose);
  char* text = nullptr;
  if (H5Dread(set.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, &text) < 0 || text == nullptr)
    throw Error(path.string() + ": cannot read " + name);
  std::string out(text);
  H5free_memory(text);
  return out;
}

}  // namespace

void WriteAcronymFile(const std::filesystem::path& path, const AcronymGrasps& g) {
  const size_t n = g.model_from_gripper.size();
  if (g.width_mm.size() != n || g.quality.size() != n || g.success.size() != n)
    throw Error(path.string() + ": one width, quality and success label per grasp needed");
  std::vector<double> transforms;
  transforms.reserve(16 * n);
  for (const Eigen::Isometry3d& t : g.model_from_gripper) {
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c)
        transforms.push_back(t.matrix()(r, c) * (r < 3 && c == 3 ? 1e-3 : 1));
    }
  }
  std::vector<double> widths, qualities;
  std::vector<int64_t> success;
  for (size_t i = 0; i < n; ++i) {
    widths.push_back(g.width_mm[i] * 1e-3);
    qualities.push_back(g.quality[i]);
    success.push_back(g.success[i]);
  }
  // HDF5 prints its own error stack for failed calls: ours names the file instead.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  Writer w(path);
  for (const char* group : {"grasps", "grasps/qualities", "grasps/qualities/flex",
                            "grasps/qualities/cadsynth", "gripper", "object"})
    w.Group(group);
  const hsize_t count = n;
  w.Doubles("grasps/transforms", {count, 4, 4}, transforms.data());
  w.Int64s("grasps/qualities/flex/object_in_gripper", {count}, success.data());
  w.Doubles("grasps/qualities/cadsynth/force_closure", {count}, qualities.data());
  w.Doubles("grasps/widths", {count}, widths.data());
  w.Text("gripper/type", g.gripper);
  w.Doubles("gripper/configuration", {1}, &g.gripper_configuration);
  w.Text("object/file", g.object_file);
  w.Scalar("object/scale", g.object_scale);
  // Mass and density only when known (a part's material is not: 0 means unknown).
  if (g.mass_kg > 0) w.Scalar("object/mass", g.mass_kg);
  if (g.density > 0) w.Scalar("object/density", g.density);
  w.Scalar("object/friction", g.friction);
  w.Scalar("object/volume", g.volume_m3);
  w.Doubles("object/com", {3}, g.com_m.data());
  if (g.cup_diameter_mm > 0) {
    const size_t m = g.suction_points_mm.size();
    if (g.suction_approaches.size() != m || g.suction_seal.size() != m ||
        g.suction_wrench.size() != m)
      throw Error(path.string() + ": one approach, seal and wrench score per suction grasp needed");
    std::vector<double> points, approaches, score;
    for (size_t i = 0; i < m; ++i) {
      for (int k = 0; k < 3; ++k) {
        points.push_back(1e-3 * g.suction_points_mm[i][k]);
        approaches.push_back(g.suction_approaches[i][k]);
      }
      score.push_back(g.suction_seal[i] * g.suction_wrench[i]);
    }
    w.Group("suction");
    w.Group("suction/qualities");
    const hsize_t rows = m;
    w.Doubles("suction/points", {rows, 3}, points.data());
    w.Doubles("suction/approaches", {rows, 3}, approaches.data());
    w.Doubles("suction/qualities/seal", {rows}, g.suction_seal.data());
    w.Doubles("suction/qualities/wrench", {rows}, g.suction_wrench.data());
    w.Doubles("suction/qualities/score", {rows}, score.data());
    w.Scalar("suction/cup_diameter", 1e-3 * g.cup_diameter_mm);
    w.Scalar("suction/vacuum", 1e3 * g.cup_vacuum_kpa);
  }
  w.Close();
}

AcronymGrasps ReadAcronymFile(const std::filesystem::path& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) throw Error(path.string() + ": not an HDF5 file");
  AcronymGrasps g;
  const std::vector<double> t =
      ReadAll<double>(file.get(), "grasps/transforms", H5T_NATIVE_DOUBLE, path);
  if (t.size() % 16 != 0) throw Error(path.string() + ": grasps/transforms is not N x 4 x 4");
  for (size_t i = 0; i < t.size() / 16; ++i) {
    Eigen::Matrix4d m;
    for (int k = 0; k < 16; ++k) m(k / 4, k % 4) = t[16 * i + k] * (k % 4 == 3 && k < 12 ? 1e3 : 1);
    g.model_from_gripper.emplace_back(m);
  }
  for (double w : ReadAll<double>(file.get(), "grasps/widths", H5T_NATIVE_DOUBLE, path))
    g.width_mm.push_back(w * 1e3);
  g.quality = ReadAll<double>(file.get(), "grasps/qualities/cadsynth/force_closure",
                              H5T_NATIVE_DOUBLE, path);
  for (int64_t s : ReadAll<int64_t>(file.get(), "grasps/qualities/flex/object_in_gripper",
                                    H5T_NATIVE_INT64, path))
    g.success.push_back(static_cast<int>(s));
  g.gripper = ReadText(file.get(), "gripper/type", path);
  g.gripper_configuration =
      ReadAll<double>(file.get(), "gripper/configuration", H5T_NATIVE_DOUBLE, path).at(0);
  g.object_file = ReadText(file.get(), "object/file", path);
  const auto scalar = [&](const char* name) {
    return ReadAll<double>(file.get(), name, H5T_NATIVE_DOUBLE, path).at(0);
  };
  g.object_scale = scalar("object/scale");
  const auto optional = [&](const char* name) {
    return H5Lexists(file.get(), name, H5P_DEFAULT) > 0 ? scalar(name) : 0.0;
  };
  g.mass_kg = optional("object/mass");
  g.density = optional("object/density");
  g.friction = scalar("object/friction");
  g.volume_m3 = scalar("object/volume");
  const std::vector<double> com =
      ReadAll<double>(file.get(), "object/com", H5T_NATIVE_DOUBLE, path);
  if (com.size() == 3) g.com_m = Eigen::Vector3d(com[0], com[1], com[2]);
  if (H5Lexists(file.get(), "suction", H5P_DEFAULT) > 0) {
    const auto all = [&](const char* name) {
      return ReadAll<double>(file.get(), name, H5T_NATIVE_DOUBLE, path);
    };
    const std::vector<double> points = all("suction/points"),
                              approaches = all("suction/approaches");
    if (points.size() % 3 != 0 || approaches.size() != points.size())
      throw Error(path.string() + ": suction/points and suction/approaches are not M x 3");
    for (size_t i = 0; i < points.size() / 3; ++i) {
      g.suction_points_mm.emplace_back(1e3 * points[3 * i], 1e3 * points[3 * i + 1],
                                       1e3 * points[3 * i + 2]);
      g.suction_approaches.emplace_back(approaches[3 * i], approaches[3 * i + 1],
                                        approaches[3 * i + 2]);
    }
    g.suction_seal = all("suction/qualities/seal");
    g.suction_wrench = all("suction/qualities/wrench");
    if (g.suction_seal.size() != g.suction_points_mm.size() ||
        g.suction_wrench.size() != g.suction_points_mm.size())
      throw Error(path.string() + ": one seal and wrench score per suction point needed");
    g.cup_diameter_mm = 1e3 * scalar("suction/cup_diameter");
    g.cup_vacuum_kpa = 1e-3 * scalar("suction/vacuum");
  }
  return g;
}

}  // namespace cadsynth
