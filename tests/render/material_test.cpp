// Materials, textures and images of the physically based mode.
#include "render/material.h"

#include <cmath>
#include <fstream>
#include <limits>

#include <opencv2/imgcodecs.hpp>

#include "tests/image_support.h"

#include <gtest/gtest.h>

#include "cad/core/error.h"
#include "render/image.h"
#include "render/sampling.h"
#include "tests/test_support.h"

namespace cadsynth {
namespace {

TEST(Material, EveryPresetIsValidAndMetalsKeepTheirColour) {
  const std::vector<std::string> names = MaterialPresetNames();
  EXPECT_GE(names.size(), 14u);
  for (const std::string& name : names) {
    Material m;
    ASSERT_TRUE(MaterialPreset(name, &m)) << name;
    std::string why;
    EXPECT_TRUE(m.Check(&why)) << name << ": " << why;
    // A metal's colour is the metal's; paints and plastics take the part's.
    if (m.surface.metallic >= 1) {
      EXPECT_FALSE(m.base_from_part) << name;
    }
  }
  Material m;
  EXPECT_FALSE(MaterialPreset("unobtainium", &m));
  ASSERT_TRUE(MaterialPreset("aluminium", &m));
  EXPECT_NEAR(m.surface.base_color[0], 0.91f, 1e-6);  // aluminium's reflectance at normal incidence
  EXPECT_GT(m.surface.anisotropic, 0.0f);             // brushed
}

TEST(Material, ValueNoiseIsSmoothBoundedAndSeeded) {
  float lo = 1, hi = 0, largest_step = 0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3f p(0.013f * i - 100, 0.007f * i, -0.011f * i);
    const float v = ValueNoise(p, 3);
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    largest_step =
        std::max(largest_step, std::abs(ValueNoise(p + Eigen::Vector3f(1e-3f, 0, 0), 3) - v));
  }
  EXPECT_GE(lo, 0.0f);
  EXPECT_LT(hi, 1.0f);
  EXPECT_GT(hi - lo, 0.5f);  // it does vary
  // Continuous: the quintic fade's slope is at most 15/8 per lattice cell per corner difference.
  EXPECT_LT(largest_step, 2e-3f);
  EXPECT_NE(ValueNoise({0.5f, 0.5f, 0.5f}, 1), ValueNoise({0.5f, 0.5f, 0.5f}, 2));
}

// ValueNoise as render/material.h specifies it, one corner at a time (the library evaluates four
// corners at once with vector instructions; it must give the same bits).
float SpecifiedValueNoise(const Eigen::Vector3f& p, uint64_t seed) {
  const auto lattice = [&](int32_t x, int32_t y, int32_t z) {
    uint32_t h =
        static_cast<uint32_t>(seed ^ (seed >> 32)) ^ (static_cast<uint32_t>(x) * 0x8DA6B343u) ^
        (static_cast<uint32_t>(y) * 0xD8163841u) ^ (static_cast<uint32_t>(z) * 0xCB1AB31Fu);
    h ^= h >> 16;
    h *= 0x7FEB352Du;
    h ^= h >> 15;
    h *= 0x846CA68Bu;
    h ^= h >> 16;
    return static_cast<float>(h >> 8) / 16777216.0f;
  };
  const auto fade = [](float t) { return t * t * t * (t * (t * 6 - 15) + 10); };
  const Eigen::Vector3f f(std::floor(p.x()), std::floor(p.y()), std::floor(p.z()));
  const int32_t x = static_cast<int32_t>(f.x()), y = static_cast<int32_t>(f.y()),
                z = static_cast<int32_t>(f.z());
  const float tx = fade(p.x() - f.x()), ty = fade(p.y() - f.y()), tz = fade(p.z() - f.z());
  float c[2][2];
  for (int dz = 0; dz < 2; ++dz) {
    for (int dy = 0; dy < 2; ++dy) {
      const float a = lattice(x, y + dy, z + dz), b = lattice(x + 1, y + dy, z + dz);
      c[dz][dy] = a + tx * (b - a);
    }
  }
  const float near = c[0][0] + ty * (c[0][1] - c[0][0]);
  const float far = c[1][0] + ty * (c[1][1] - c[1][0]);
  return near + tz * (far - near);
}

TEST(Material, ValueNoiseIsItsSpecificationToTheBit) {
  int different = 0;
  for (int i = 0; i < 100000; ++i) {
    // Both signs, cell boundaries (every 64th point is on the lattice) and large coordinates.
    const float scale = i % 3 == 0 ? 1.0f : (i % 3 == 1 ? 37.0f : 5000.0f);
    Eigen::Vector3f p(std::sin(0.7f * i) * scale, std::cos(1.3f * i) * scale,
                      std::sin(2.9f * i + 1) * scale);
    if (i % 64 == 0) p = p.array().round().matrix();
    const uint64_t seed = 0x9E3779B97F4A7C15ull * static_cast<uint64_t>(i % 7 + 1);
    different += ValueNoise(p, seed) != SpecifiedValueNoise(p, seed);
  }
  EXPECT_EQ(different, 0);
  // On a lattice point the noise is that point's value.
  EXPECT_EQ(ValueNoise(Eigen::Vector3f(-3, 7, 2), 11),
            SpecifiedValueNoise(Eigen::Vector3f(-3, 7, 2), 11));
}

// FractalNoise as render/material.h specifies it, one octave at a time (the library evaluates
// four octaves at once with vector instructions; it must give the same bits).
TEST(Material, FractalNoiseIsItsOctavesSummedInOrderToTheBit) {
  const auto specified = [](const Eigen::Vector3f& p, int octaves, uint64_t seed, float footprint) {
    float sum = 0, amplitude = 0.5f, total = 0, cell = 1;
    Eigen::Vector3f q = p;
    for (int o = 0; o < octaves; ++o) {
      sum += amplitude *
             (cell < footprint ? 0.5f : ValueNoise(q, Hash(seed, static_cast<uint64_t>(o))));
      total += amplitude;
      amplitude *= 0.5f;
      cell *= 0.5f;
      q = Eigen::Vector3f(1.6f * q.x() + 1.2f * q.y(), -1.2f * q.x() + 1.6f * q.y(), 2.0f * q.z());
    }
    return sum / total;
  };
  int different = 0, compared = 0;
  for (int i = 0; i < 20000; ++i) {
    const float scale = i % 3 == 0 ? 1.0f : (i % 3 == 1 ? 37.0f : 5000.0f);
    const Eigen::Vector3f p(std::sin(0.7f * i) * scale, std::cos(1.3f * i) * scale,
                            std::sin(2.9f * i + 1) * scale);
    const int octaves = 1 + i % 10;  // one to ten: whole and part-filled groups of four
    // No footprint, one that drops some octaves, one that drops all.
    const float footprint = i % 4 == 0 ? 0.0f : (i % 4 == 3 ? 2.0f : std::ldexp(1.0f, -(i % 7)));
    const uint64_t seed = 0x9E3779B97F4A7C15ull * static_cast<uint64_t>(i % 5 + 1);
    different +=
        FractalNoise(p, octaves, seed, footprint) != specified(p, octaves, seed, footprint);
    ++compared;
  }
  // Beyond FastFloor's clamp (+-1e9) and not a number: the same values, NaN where it is NaN.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const Eigen::Vector3f& p :
       {Eigen::Vector3f(2e9f, -3e9f, 0.5f), Eigen::Vector3f(-2e9f, 1.5f, 4e9f),
        Eigen::Vector3f(nan, 0.25f, 0.5f), Eigen::Vector3f(0.5f, 0.25f, nan)}) {
    for (int octaves = 1; octaves <= 6; ++octaves) {
      const float a = FractalNoise(p, octaves, 7), b = specified(p, octaves, 7, 0.0f);
      different += !(a == b || (std::isnan(a) && std::isnan(b)));
      ++compared;
    }
  }
  EXPECT_EQ(different, 0) << "of " << compared;
}

TEST(Material, NoiseFinerThanTheFootprintAveragesToItsMean) {
  const Eigen::Vector3f p(1.3f, -2.7f, 0.4f);
  // Every octave finer than the footprint: the mean, exactly.
  EXPECT_FLOAT_EQ(FractalNoise(p, 4, 9, 2.0f), 0.5f);
  // No footprint: every octave counts; a footprint of a quarter cell drops the last two of four.
  const float full = FractalNoise(p, 4, 9, 0.0f);
  const float filtered = FractalNoise(p, 4, 9, 0.3f);
  EXPECT_NE(full, filtered);
  EXPECT_NEAR(filtered, full, (0.125f + 0.0625f) / (0.5f + 0.25f + 0.125f + 0.0625f));
  // Averaging the unfiltered noise over a large patch gives the filtered value.
  double sum = 0;
  const int n = 200;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j)
      sum += FractalNoise(Eigen::Vector3f(0.37f * i, 0.53f * j, 0.29f * (i + j)), 3, 4);
  }
  EXPECT_NEAR(sum / (n * n), 0.5, 0.01);
}

TEST(Material, CheckerAndRustBlendAndRustIsNotMetal) {
  Texture checker;
  checker.kind = Texture::Kind::kChecker;
  checker.scale_mm = 10;
  checker.color = {0.1f, 0.2f, 0.3f};
  const Eigen::Vector3f n = Eigen::Vector3f::UnitZ();
  EXPECT_EQ(EvalTexture(checker, {5, 5, 5}, n, nullptr).mix, 0.0f);   // cell (0, 0, 0)
  EXPECT_EQ(EvalTexture(checker, {15, 5, 5}, n, nullptr).mix, 1.0f);  // cell (1, 0, 0)
  PrincipledParams steel;
  steel.metallic = 1;
  steel.base_color = Eigen::Vector3f::Constant(0.56f);
  const PrincipledParams painted =
      ApplyTexture(steel, EvalTexture(checker, {15, 5, 5}, n, nullptr));
  EXPECT_EQ(painted.base_color, checker.color);
  EXPECT_EQ(painted.metallic, 0.0f);
  // Rust covers about `amount` of the surface.
  Texture rust;
  rust.kind = Texture::Kind::kRust;
  rust.scale_mm = 5;
  for (const float amount : {0.2f, 0.5f, 0.8f}) {
    rust.amount = amount;
    double covered = 0;
    for (int i = 0; i < 4000; ++i) {
      const Eigen::Vector3f p(1.7f * (i % 63), 2.3f * (i / 63), 0.0f);
      covered += EvalTexture(rust, p, n, nullptr).mix;
    }
    EXPECT_NEAR(covered / 4000, amount, 0.2) << amount;
  }
}

TEST(Material, ScratchesAreThinLinesWhoseNumberFollowsTheAmount) {
  Texture t;
  t.kind = Texture::Kind::kScratches;
  t.scale_mm = 20;
  const Eigen::Vector3f n = Eigen::Vector3f::UnitZ();
  double previous = -1;
  for (const float amount : {0.0f, 0.3f, 1.0f}) {
    t.amount = amount;
    int on = 0;
    for (int i = 0; i < 40000; ++i) {
      const Eigen::Vector3f p(0.37f * (i % 200), 0.41f * (i / 200), 3.0f);
      const TextureSample s = EvalTexture(t, p, n, nullptr, 0.01f);
      ASSERT_GE(s.roughness_offset, -t.roughness_amount);
      ASSERT_LE(s.roughness_offset, 0.0f);  // smoother on a scratch, never rougher
      on += s.roughness_offset < -0.5f * t.roughness_amount;
    }
    const double fraction = on / 40000.0;
    if (amount == 0) {
      EXPECT_EQ(on, 0);
    }
    EXPECT_GT(fraction, previous);
    EXPECT_LT(fraction, 0.2);  // thin lines, not patches
    previous = fraction;
  }
  // Seen from afar (a footprint of many scratch widths), only a faint average remains.
  EXPECT_NEAR(EvalTexture(t, {1, 2, 3}, n, nullptr, 30.0f).roughness_offset, -0.2f * 0.02f, 1e-4);
}

TEST(Material, ImagesAreLinearAndBadOnesAreNamed) {
  testing::ScratchDir dir;
  // sRGB 128 is linear ((128/255 + 0.055) / 1.055)^2.4 = 0.2158.
  testing::Imwrite((dir / "grey.png").string(), cv::Mat(4, 8, CV_8UC3, cv::Scalar(128, 128, 128)));
  const auto image = LoadLinearImage(dir / "grey.png");
  EXPECT_EQ(image->width, 8);
  EXPECT_EQ(image->height, 4);
  EXPECT_NEAR(image->at(3, 2)[1], 0.2158f, 1e-4);
  // Float images are taken as they are (EXR: linear radiance).
  testing::Imwrite((dir / "sky.exr").string(), cv::Mat(2, 4, CV_32FC3, cv::Scalar(0.5, 2.0, 7.5)));
  const auto hdr = LoadLinearImage(dir / "sky.exr");
  EXPECT_FLOAT_EQ(hdr->at(1, 1)[0], 7.5f);  // R (OpenCV writes BGR)
  EXPECT_FLOAT_EQ(hdr->at(1, 1)[2], 0.5f);
  std::ofstream(dir / "fake.hdr") << "#?RADIANCE\nnonsense";
  for (const char* name : {"fake.hdr", "missing.png"}) {
    try {
      LoadLinearImage(dir / name);
      FAIL() << name;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  }
  // Image textures project triplanarly: on a face looking along z, the image's (x, -y).
  Texture t;
  t.kind = Texture::Kind::kImage;
  t.scale_mm = 8;
  const TextureSample s = EvalTexture(t, {1, -1, 0}, Eigen::Vector3f::UnitZ(), image.get());
  EXPECT_EQ(s.mix, 1.0f);
  EXPECT_NEAR(s.color_mix[0], 0.2158f, 1e-4);
  // An image is the base colour (Blender's Base Color input): a metal stays a metal under it, where
  // a checker's paint is not metal (CheckerAndRustBlendAndRustIsNotMetal).
  PrincipledParams steel;
  steel.metallic = 1;
  const PrincipledParams imaged = ApplyTexture(steel, s);
  EXPECT_EQ(imaged.metallic, 1.0f);
  EXPECT_NEAR(imaged.base_color[0], 0.2158f, 1e-4);
}

}  // namespace
}  // namespace cadsynth
