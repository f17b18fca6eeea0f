#include "dataset/paper_layout.h"

#include <matio.h>

#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "tests/image_support.h"

#include <gtest/gtest.h>

#include "cad/shape.h"
#include "dataset/grasp.h"
#include "dataset/output_formats.h"
#include "render/renderer.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

using nlohmann::json;

// A 100 x 60 x 40 mm box and a pin on the floor, seen from above at an angle.
struct TwoParts {
  std::vector<Part> parts = {MakePart("block", MakeBox(100, 60, 40), TessellationOptions{}),
                             MakePart("pin", MakeCylinder(8, 50), TessellationOptions{})};
  Scene scene;
  Frame frame;
  explicit TwoParts(const Distortion& distortion = {}) {
    scene.instances = {
        Instance{0, "block", Eigen::Isometry3d(Eigen::Translation3d(0, 0, 20))},
        Instance{1, "pin", Eigen::Translation3d(80, 0, 25) * Eigen::Isometry3d::Identity()}};
    Camera camera;
    camera.world_from_cam = WorldFromCamOnSphere({0, 0, 0}, 0.3, 0.9, 500.0);
    camera.intrinsics.distortion = distortion;
    // With distortion, the parts near the image's left edge, where the lens bends rays most.
    if (distortion.active()) camera.intrinsics.cx = 100.0;
    frame = Renderer(parts, scene).Render(camera);
  }
};

TEST(Grasp, BackProjectedPointsLieOnTheObject) {
  // Also through a strongly distorting lens (the pinhole's rays would miss the box by about
  // 10 mm where the parts are, 220 px left of the principal point).
  for (const TwoParts& s : {TwoParts(), TwoParts(Distortion{-0.25, 0.05, 0.002, -0.001})})
    for (int i = 0; i < 2; ++i) {
      const std::vector<Eigen::Vector3f> points = BackProjectInstance(s.frame, i, 0.1);
      EXPECT_EQ(static_cast<int>(points.size()),
                s.frame.instances[i].px_count_visib);  // every depth is valid
      // Back in the model frame (mm), every point is on the part's box, up to depth rounding.
      const Eigen::Isometry3d model_from_cam = s.frame.instances[i].cam_from_model.inverse();
      const Eigen::AlignedBox3d box = s.parts[i].mesh.Bounds();
      double worst = 0;
      for (const Eigen::Vector3f& p : points) {
        const Eigen::Vector3d q = model_from_cam * (p.cast<double>() * 1000.0);
        worst = std::max(worst, box.exteriorDistance(q));
      }
      EXPECT_LT(worst, 0.2) << "mm outside the box";
    }
}

TEST(Grasp, NpyHeaderIsWhatNumpyReads) {
  const std::string npy = EncodeNpy({{1, 2, 3}, {4, 5, 6}});
  ASSERT_EQ(npy.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  const size_t header = static_cast<uint8_t>(npy[8]) | static_cast<uint8_t>(npy[9]) << 8;
  EXPECT_EQ((10 + header) % 64, 0u);
  EXPECT_EQ(npy[10 + header - 1], '\n');
  EXPECT_NE(npy.find("'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"),
            std::string::npos);
  ASSERT_EQ(npy.size(), 10 + header + 6 * sizeof(float));
  float last;
  std::memcpy(&last, &npy[npy.size() - 4], 4);
  EXPECT_EQ(last, 6.0f);
}

std::vector<double> ReadMat(mat_t* mat, const char* name, std::vector<size_t>* dims) {
  matvar_t* var = Mat_VarRead(mat, name);
  EXPECT_NE(var, nullptr) << name;
  if (var == nullptr) return {};
  dims->assign(var->dims, var->dims + var->rank);
  size_t n = 1;
  for (size_t d : *dims) n *= d;
  const double* data = static_cast<const double*>(var->data);
  std::vector<double> values(data, data + n);
  Mat_VarFree(var);
  return values;
}

TEST(PaperLayout, MaskMetaAndPvn3dMatchTheFrame) {
  testing::ScratchDir dir;
  const TwoParts s;
  BopOptions options;
  options.pvn3d_meta = true;  // turns the paper layout on: its meta files sit beside its images
  BopSceneWriter bop(dir.path(), 0, options, {1, 2});
  bop.WriteFrame(5, s.frame);
  FormatScene scene{dir.path(), 0, options, std::vector<FormatInstance>(2)};
  for (int i = 0; i < 2; ++i) {
    scene.instances[i].obj_id = i + 1;
    scene.instances[i].object_class.id = 1;
    scene.instances[i].object_class.name = "block";
    scene.instances[i].name = s.scene.instances[i].name;
    scene.instances[i].world_from_model = s.scene.instances[i].world_from_model;
  }
  const std::vector<std::unique_ptr<FrameWriter>> writers = MakeFrameWriters(scene);
  ASSERT_EQ(writers.size(), 2u);  // the paper layout, then pvn3d's meta files
  for (const auto& writer : writers) {
    writer->WriteFrame(
        5, s.frame,
        {bop.scene_dir() / "rgb" / "000005.png", bop.scene_dir() / "depth" / "000005.png"},
        nullptr);
  }
  const auto root = dir / "paper" / "000000";

  // Colour and depth are BOP's files (linked, not re-encoded).
  EXPECT_TRUE(std::filesystem::equivalent(root / "rgb" / "000005.png",
                                          bop.scene_dir() / "rgb" / "000005.png"));
  // The mask carries each object's obj_id where that object is visible.
  const cv::Mat mask =
      testing::Imread((root / "mask" / "000005.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(mask.type(), CV_8UC1);
  for (int i = 0; i < 2; ++i)
    EXPECT_EQ(cv::countNonZero(mask == i + 1), s.frame.instances[i].px_count_visib);

  std::ifstream in(root / "meta" / "000005.json");
  const json meta = json::parse(in);
  EXPECT_EQ(meta["depth_scale"], 0.1);
  Eigen::Matrix4d c_w, o_c, o_w;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      c_w(r, c) = meta["T_C_W"][r][c];
      o_c(r, c) = meta["objects"][1]["T_O_C"][r][c];
      o_w(r, c) = meta["objects"][1]["T_O_W"][r][c];
    }
  }
  EXPECT_TRUE((c_w.inverse() * o_w).isApprox(o_c, 1e-9));  // the paper's T_O^C = (T_C^W)^-1 T_O^W
  EXPECT_TRUE(o_c.isApprox(s.frame.instances[1].cam_from_model.matrix(), 1e-12));
  EXPECT_EQ(meta["objects"][1]["class_name"], "block");

  mat_t* mat = Mat_Open((root / "meta" / "000005-meta.mat").c_str(), MAT_ACC_RDONLY);
  ASSERT_NE(mat, nullptr);
  std::vector<size_t> dims;
  EXPECT_EQ(ReadMat(mat, "cls_indexes", &dims), (std::vector<double>{1, 2}));
  const std::vector<double> poses = ReadMat(mat, "poses", &dims);
  EXPECT_EQ(dims, (std::vector<size_t>{3, 4, 2}));
  const Eigen::Isometry3d& pin = s.frame.instances[1].cam_from_model;
  EXPECT_NEAR(poses[0 + 3 * 1 + 12], pin.linear()(0, 1), 1e-12);              // R(0, 1) of the pin
  EXPECT_NEAR(poses[2 + 3 * 3 + 12], pin.translation().z() / 1000.0, 1e-12);  // t_z in metres
  EXPECT_EQ(ReadMat(mat, "factor_depth", &dims), (std::vector<double>{10000.0}));  // 0.1 mm units
  const std::vector<double> k = ReadMat(mat, "intrinsic_matrix", &dims);
  EXPECT_EQ(k[6], s.frame.camera.intrinsics.cx);  // column-major: (0, 2)
  ReadMat(mat, "center", &dims);
  EXPECT_EQ(dims, (std::vector<size_t>{2, 2}));
  Mat_Close(mat);
}

TEST(OutputFormats, EveryFormatIsOneRowWithAUniqueNameAndAFlag) {
  std::set<std::string> names;
  for (const OutputFormat& format : OutputFormats()) {
    EXPECT_TRUE(names.insert(format.name).second) << format.name;
    // Only bop is unconditional; every other format has its BopOptions flag.
    EXPECT_EQ(format.enabled == nullptr, std::string(format.name) == "bop") << format.name;
    if (format.implies != nullptr) {
      EXPECT_NE(FindOutputFormat(format.implies), nullptr);
    }
  }
  EXPECT_EQ(FindOutputFormat("dexnet"), nullptr);
  // No flag, no writer: a dataset of BOP and COCO alone has no derived writers.
  BopOptions options;
  options.coco = true;
  EXPECT_TRUE(MakeFrameWriters({"/nonexistent", 0, options, {}}).empty());
}

}  // namespace
}  // namespace cadsynth
