// The unit hypercube the search works in: discrete parameters only ever take whole values.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "shaders/parameter_space.h"

namespace proctex {
namespace {

ShaderDecl star_like() {
  return parse_shader("shaders/test/star.cl", R"(// @shader "x"
// @param int   points = 5 [3, 12] "Points"
// @param float size = 0.1 [0.01, 1] log "Size"
// @param float ratio = 0.5 [0.1, 0.9] "Inner radius ratio"
// @param color fg = (1, 1, 1) "Star colour"
// @param enum  style = flat {flat, soft} "Style"
// @param float fixed_one = 0.3 [0, 1] fixed "Not searched"
float3 shade(float2 p, float fw, uint seed, const Params P) { return P.fg; }
)");
}

TEST(ParameterSpace, DimensionsSkipFixedAndPinned) {
  const ShaderDecl d = star_like();
  EXPECT_EQ(ParameterSpace(d).dimensions(), 7);  // points, size, ratio, 3 colour channels, style
  EXPECT_EQ(ParameterSpace(d, d.default_packed(), {"ratio", "fg"}).dimensions(), 3);
}

TEST(ParameterSpace, DiscreteParametersTakeOnlyWholeValues) {
  const ShaderDecl d = star_like();
  const ParameterSpace space(d);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<int> seen(13, 0);
  for (int i = 0; i < 2000; ++i) {
    std::vector<double> x(space.dimensions());
    for (auto& v : x) v = u(rng);
    const auto packed = space.to_packed(x);
    const float points = packed[d.find("points")->offset];
    ASSERT_EQ(points, std::round(points));
    ASSERT_GE(points, 3);
    ASSERT_LE(points, 12);
    seen[static_cast<int>(points)]++;
    const float style = packed[d.find("style")->offset];
    ASSERT_TRUE(style == 0.0f || style == 1.0f);
  }
  // Equal bins: every count from 3 to 12 is reachable with similar frequency.
  for (int k = 3; k <= 12; ++k) EXPECT_GT(seen[k], 120) << k;
}

TEST(ParameterSpace, LogAndLinearMappingRoundTrip) {
  const ShaderDecl d = star_like();
  const ParameterSpace space(d);
  std::vector<double> x(space.dimensions(), 0.5);
  const auto packed = space.to_packed(x);
  EXPECT_NEAR(packed[d.find("size")->offset], 0.1f, 1e-5f);  // geometric midpoint of [0.01, 1]
  EXPECT_NEAR(packed[d.find("ratio")->offset], 0.5f, 1e-6f);
  const auto back = space.to_unit(packed);
  EXPECT_NEAR(back[1], 0.5, 1e-6);
  EXPECT_NEAR(back[2], 0.5, 1e-6);
}

TEST(ParameterSpace, FixedParametersKeepBaseValues) {
  const ShaderDecl d = star_like();
  auto base = d.default_packed();
  base[d.find("ratio")->offset] = 0.77f;
  const ParameterSpace space(d, base, {"ratio"});
  const auto packed = space.to_packed(std::vector<double>(space.dimensions(), 0.0));
  EXPECT_FLOAT_EQ(packed[d.find("ratio")->offset], 0.77f);
  EXPECT_FLOAT_EQ(packed[d.find("fixed_one")->offset], 0.3f);
  EXPECT_FLOAT_EQ(packed[d.find("points")->offset], 3.0f);
}

TEST(ParameterSpace, SnapMovesDiscreteCoordinatesToBinCentres) {
  const ParameterSpace space(star_like());
  std::vector<double> x(space.dimensions(), 0.01);
  const auto s = space.snap(x);
  EXPECT_NEAR(s[0], 0.05, 1e-9);  // points: 10 levels, first bin centre
  EXPECT_NEAR(s[1], 0.01, 1e-6);  // continuous stays
}

}  // namespace
}  // namespace proctex
