#include "cad/core/random.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace cadsynth {
namespace {

TEST(RandomStreams, NamesAndIdsAreUniqueAndFnv1aIsTheStandardOne) {
  // FNV-1a test vectors (Fowler, Noll and Vo).
  EXPECT_EQ(Fnv1a64(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(Fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(Fnv1a64("foobar"), 0x85944171f73967e8ull);
  std::set<std::string_view> names;
  std::set<uint64_t> ids;
  for (const RandomStream& s : kRandomStreams) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_TRUE(ids.insert(s.id()).second) << s.name;
    EXPECT_FALSE(s.what.empty()) << s.name;
  }
  EXPECT_GE(names.size(), 14u);
}

// docs/recipes.md's table of streams lists exactly these, in this order.
TEST(RandomStreams, ReadmeListsEveryStream) {
  std::ifstream in(std::string(CADSYNTH_SOURCE_DIR) + "/docs/recipes.md");
  ASSERT_TRUE(in);
  std::vector<std::string> listed;
  bool inside = false;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("### Random streams", 0) == 0) inside = true;
    if (inside && line.rfind("### ", 0) == 0 && line != "### Random streams") break;
    if (inside && line.rfind("| `", 0) == 0)
      listed.push_back(line.substr(3, line.find('`', 3) - 3));
  }
  std::vector<std::string> streams;
  for (const RandomStream& s : kRandomStreams) streams.emplace_back(s.name);
  EXPECT_EQ(listed, streams);
}

TEST(RandomStreams, KnownValuesDoNotChange) {
  // The draws are part of the recipe format: the same seed must give the same scene forever.
  EXPECT_EQ(UniformDraw(0, streams::kViewYaw, 0), 0.35975937202718167);
  EXPECT_EQ(UniformDraw(2026, streams::kCopyYaw, 7), 0.23708567615439158);
  EXPECT_EQ(UniformDraw(1, "family.param.teeth", 3), 0.36559306266537139);
}

TEST(RandomStreams, StreamsSeedsAndIndicesGiveIndependentDraws) {
  EXPECT_EQ(UniformDraw(7, streams::kViewYaw, 99), UniformDraw(7, streams::kViewYaw, 99));
  EXPECT_EQ(UniformDraw(7, streams::kViewYaw, 99), UniformDraw(7, "view.yaw", 99));
  EXPECT_NE(UniformDraw(7, streams::kViewYaw, 99), UniformDraw(8, streams::kViewYaw, 99));
  EXPECT_NE(UniformDraw(7, streams::kViewYaw, 99), UniformDraw(7, streams::kViewPitch, 99));
  // Every stream, 20,000 draws in 10 bins: chi-square below 27.88, the 0.1% critical value for 9
  // degrees of freedom; neighbouring indices and two streams at the same index uncorrelated.
  for (const RandomStream& s : kRandomStreams) {
    SCOPED_TRACE(std::string(s.name));
    std::vector<int> bins(10, 0);
    double previous = 0.5, lag = 0, cross = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      const double u = UniformDraw(1, s, static_cast<uint64_t>(i));
      ASSERT_GE(u, 0.0);
      ASSERT_LT(u, 1.0);
      ++bins[static_cast<int>(u * 10)];
      lag += (u - 0.5) * (previous - 0.5);
      cross += (u - 0.5) * (UniformDraw(1, "family.param.teeth", static_cast<uint64_t>(i)) - 0.5);
      previous = u;
    }
    double chi2 = 0;
    for (int count : bins) chi2 += (count - n / 10.0) * (count - n / 10.0) / (n / 10.0);
    EXPECT_LT(chi2, 27.88);
    // Correlations of independent uniforms: sd 1/sqrt(n) = 0.007 of the variance 1/12.
    EXPECT_LT(std::abs(lag / n / (1.0 / 12)), 0.03);
    EXPECT_LT(std::abs(cross / n / (1.0 / 12)), 0.03);
  }
}

TEST(RandomStreams, NormalPairIsBoxMuller) {
  // Against the formula through libm, over a grid of both uniforms (every quadrant and octant
  // boundary of 2 pi u2) and at the ends: u1 = 0 (r = 0) and the largest draw below 1
  // (r = sqrt(2 * 53 ln 2) = 8.57).
  const double largest = 1.0 - 0x1.0p-53;
  std::vector<double> u1s = {0.0, largest, 0.5, 1e-300, 0.9999};
  std::vector<double> u2s = {0.0, largest, 0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875};
  for (int i = 1; i < 1000; ++i) {
    u1s.push_back(i / 1000.0);
    u2s.push_back(UniformDraw(3, streams::kImageNoise, i));
  }
  double worst = 0;
  for (double u1 : u1s) {
    for (double u2 : u2s) {
      double z0, z1;
      NormalPair(u1, u2, &z0, &z1);
      const double r = std::sqrt(-2.0 * std::log(1.0 - u1));
      worst = std::max({worst, std::abs(z0 - r * std::cos(2.0 * M_PI * u2)),
                        std::abs(z1 - r * std::sin(2.0 * M_PI * u2))});
    }
  }
  EXPECT_LT(worst, 1e-10);
  double z0, z1;
  NormalPair(largest, 0.0, &z0, &z1);
  EXPECT_NEAR(z0, std::sqrt(2 * 53 * std::log(2.0)), 1e-12);
  EXPECT_EQ(z1, 0.0);
  NormalPair(0.0, 0.3, &z0, &z1);
  EXPECT_EQ(z0, 0.0);
  EXPECT_EQ(z1, 0.0);
}

TEST(RandomStreams, NormalPairsFloatIsBoxMullerInSinglePrecision) {
  // Against the formula through libm in double precision, for bits that put u1 and u2 on a grid
  // (every octant boundary of 2 pi u2) and at the ends of their 23-bit steps, and for drawn bits.
  std::vector<uint64_t> bits;
  const auto of = [](uint64_t a, uint64_t b) { return (a << 41) | (b << 18); };
  for (uint64_t a : {0ull, 1ull, 0x3fffffull, 0x400000ull, 0x7fffffull})
    for (uint64_t b = 0; b <= 8; ++b) bits.push_back(of(a, std::min<uint64_t>(b << 20, 0x7fffff)));
  for (int i = 0; i < 20000; ++i) bits.push_back(random_detail::DrawBits(5, 77, i));
  std::vector<float> z0(bits.size()), z1(bits.size());
  NormalPairsFloat(bits.data(), static_cast<int>(bits.size()), z0.data(), z1.data());
  double worst = 0;
  for (size_t i = 0; i < bits.size(); ++i) {
    const double u1 = ((bits[i] >> 41) + 0.5) / 8388608.0;
    const double u2 = (((bits[i] >> 18) & 0x7fffff) + 0.5) / 8388608.0;
    const double r = std::sqrt(-2.0 * std::log(u1));
    worst = std::max({worst, std::abs(z0[i] - r * std::cos(2.0 * M_PI * u2)),
                      std::abs(z1[i] - r * std::sin(2.0 * M_PI * u2))});
  }
  EXPECT_LT(worst, 2e-6);
  // The largest |z|: u1 at the centre of the first step, sqrt(2 * 24 ln 2).
  EXPECT_NEAR(std::hypot(z0[0], z1[0]), std::sqrt(48.0 * std::log(2.0)), 1e-5);
}

TEST(RandomStreams, NormalPairsFloatHaveTheNormalsMoments) {
  // 10^6 pairs from drawn bits: mean 0, variance 1, kurtosis 3 and no correlation between the
  // two of a pair, within 5 standard errors (sd of the mean 1e-3, of the variance 1.4e-3, of the
  // fourth moment 9.8e-3, of the product's mean 1e-3); 1.96 sd holds 95 %.
  const int n = 1000000;
  std::vector<uint64_t> bits(n);
  for (int i = 0; i < n; ++i)
    bits[i] = random_detail::DrawBits(11, streams::kSensorInfrared.id(), i);
  std::vector<float> z0(n), z1(n);
  NormalPairsFloat(bits.data(), n, z0.data(), z1.data());
  double m1[2] = {0, 0}, m2[2] = {0, 0}, m4[2] = {0, 0}, cross = 0, within = 0;
  for (int i = 0; i < n; ++i) {
    const double z[2] = {z0[i], z1[i]};
    for (int c = 0; c < 2; ++c) {
      m1[c] += z[c], m2[c] += z[c] * z[c], m4[c] += z[c] * z[c] * z[c] * z[c];
      within += std::abs(z[c]) <= 1.959964;
    }
    cross += z[0] * z[1];
  }
  for (int c = 0; c < 2; ++c) {
    EXPECT_NEAR(m1[c] / n, 0.0, 5e-3);
    EXPECT_NEAR(m2[c] / n, 1.0, 7e-3);
    EXPECT_NEAR(m4[c] / n, 3.0, 5e-2);
  }
  EXPECT_NEAR(cross / n, 0.0, 5e-3);
  EXPECT_NEAR(within / (2.0 * n), 0.95, 2e-3);  // sd of the fraction: 1.5e-4 per 2e6 numbers
}

}  // namespace
}  // namespace cadsynth
