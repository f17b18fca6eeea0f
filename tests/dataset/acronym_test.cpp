// ACRONYM's grasp files: the layout its loaders read (acronym_tools/acronym.py: object/file,
// object/scale, grasps/transforms, grasps/qualities/flex/object_in_gripper), in metres.
#include "dataset/acronym.h"

#include <hdf5.h>

#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

TEST(Acronym, FileHoldsTransformsInMetresAndReadsBack) {
  testing::ScratchDir dir;
  AcronymGrasps g;
  g.object_file = "models/obj_000001.ply";
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  a.translation() = Eigen::Vector3d(10, -20, 112.2);
  Eigen::Isometry3d b(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  b.translation() = Eigen::Vector3d(0, 5, 0);
  g.model_from_gripper = {a, b};
  g.width_mm = {40, 30};
  g.quality = {1.0, 0.25};
  g.success = {1, 1};
  g.mass_kg = 0.5;
  g.com_m = Eigen::Vector3d(0.001, 0.002, 0.003);
  const std::filesystem::path path = dir / "obj_000001.h5";
  WriteAcronymFile(path, g);

  // The raw file: (2, 4, 4) float64 in metres, object_in_gripper int64, the strings.
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const hid_t set = H5Dopen2(file, "grasps/transforms", H5P_DEFAULT);
  ASSERT_GE(set, 0);
  const hid_t space = H5Dget_space(set);
  hsize_t dims[3] = {0, 0, 0};
  ASSERT_EQ(H5Sget_simple_extent_ndims(space), 3);
  H5Sget_simple_extent_dims(space, dims, nullptr);
  EXPECT_EQ(dims[0], 2u);
  EXPECT_EQ(dims[1], 4u);
  EXPECT_EQ(dims[2], 4u);
  double raw[32];
  ASSERT_GE(H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, raw), 0);
  EXPECT_DOUBLE_EQ(raw[3], 0.010);  // row 0, column 3: x in metres
  EXPECT_DOUBLE_EQ(raw[7], -0.020);
  EXPECT_DOUBLE_EQ(raw[11], 0.1122);
  EXPECT_DOUBLE_EQ(raw[15], 1.0);
  EXPECT_NEAR(raw[16 + 6], -1.0, 1e-12);  // b's rotation, row 1, column 2
  H5Sclose(space);
  H5Dclose(set);
  const hid_t labels = H5Dopen2(file, "grasps/qualities/flex/object_in_gripper", H5P_DEFAULT);
  ASSERT_GE(labels, 0);
  const hid_t type = H5Dget_type(labels);
  EXPECT_EQ(H5Tget_class(type), H5T_INTEGER);
  EXPECT_EQ(H5Tget_size(type), 8u);
  H5Tclose(type);
  H5Dclose(labels);
  EXPECT_GT(H5Lexists(file, "object/mass", H5P_DEFAULT), 0);
  EXPECT_EQ(H5Lexists(file, "object/density", H5P_DEFAULT), 0);  // unknown: not written
  H5Fclose(file);

  const AcronymGrasps back = ReadAcronymFile(path);
  ASSERT_EQ(back.model_from_gripper.size(), 2u);
  EXPECT_TRUE(back.model_from_gripper[0].isApprox(a, 1e-12));
  EXPECT_TRUE(back.model_from_gripper[1].isApprox(b, 1e-12));
  EXPECT_EQ(back.width_mm, g.width_mm);
  EXPECT_EQ(back.quality, g.quality);
  EXPECT_EQ(back.success, g.success);
  EXPECT_EQ(back.object_file, "models/obj_000001.ply");
  EXPECT_EQ(back.gripper, "panda");
  EXPECT_DOUBLE_EQ(back.object_scale, 1e-3);
  EXPECT_DOUBLE_EQ(back.gripper_configuration, 0.04);
  EXPECT_DOUBLE_EQ(back.mass_kg, 0.5);
  EXPECT_DOUBLE_EQ(back.density, 0.0);  // unknown: not written, read back as 0
  EXPECT_EQ(back.com_m, g.com_m);

  // The same grasps, the same bytes (HDF5 would record modification times by default).
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));
  WriteAcronymFile(dir / "again.h5", g);
  EXPECT_EQ(testing::ReadFile(dir / "again.h5"), testing::ReadFile(path));

  g.success.pop_back();
  EXPECT_THROW(WriteAcronymFile(dir / "bad.h5", g), Error);
  EXPECT_THROW(WriteAcronymFile(dir / "no" / "such" / "dir.h5", AcronymGrasps{}), Error);
  EXPECT_THROW(ReadAcronymFile(dir / "missing.h5"), Error);
}

}  // namespace
}  // namespace cadsynth
