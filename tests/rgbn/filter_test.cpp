// Filters on the slope field, curvature and segmentation: properties with known truth.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "rgbn/analysis.h"
#include "rgbn/filter.h"
#include "support.h"

using namespace proctex::rgbn;
using namespace rgbn_test;

namespace {

// Direct circular convolution of a height field (the test's own reference implementation).
HeightField convolve_direct(const HeightField& z, const std::vector<float>& k, int kw, int kh) {
  HeightField out = z;
  for (int y = 0; y < z.height; ++y)
    for (int x = 0; x < z.width; ++x) {
      double s = 0;
      for (int j = 0; j < kh; ++j)
        for (int i = 0; i < kw; ++i) {
          const int xx = ((x - (i - kw / 2)) % z.width + z.width) % z.width;
          const int yy = ((y - (j - kh / 2)) % z.height + z.height) % z.height;
          s += k[size_t(j) * kw + i] * z.at(xx, yy);
        }
      out.at(x, y) = float(s);
    }
  return out;
}

std::vector<float> sampled_gaussian(float sigma, int& size) {
  const int r = int(std::ceil(3 * sigma));
  size = 2 * r + 1;
  std::vector<float> g1(size);
  double sum = 0;
  for (int i = 0; i < size; ++i) sum += g1[i] = std::exp(-0.5 * (i - r) * (i - r) / (sigma * sigma));
  std::vector<float> k(size_t(size) * size);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) k[size_t(j) * size + i] = float(g1[i] * g1[j] / (sum * sum));
  return k;
}

}  // namespace

TEST(RgbnFilter, GeneralFilterOnNormalsEqualsNormalsOfFilteredHeight) {
  const HeightField z = periodic_field(40, 32, 5, 4.0f);
  const Rgbn n = from_height(z, 1.0f, true);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-0.5f, 1.0f);
  std::vector<float> k(5 * 3);
  for (float& v : k) v = u(rng);
  const Rgbn filtered = convolve(n, k, 5, 3, true);
  const Rgbn expected = from_height(convolve_direct(z, k, 5, 3), 1.0f, true);
  EXPECT_LT(max_angle(filtered, expected), 1e-3);
  EXPECT_LT(max_norm_error(filtered), 1e-6);
}

TEST(RgbnFilter, SmoothSharpenEdgeDetailMatchTheirHeightFilters) {
  const HeightField z = periodic_field(48, 48, 6, 5.0f);
  const Rgbn n = from_height(z, 1.0f, true);
  int s1 = 0, s2 = 0;
  const auto g1 = sampled_gaussian(1.5f, s1);
  const auto g2 = sampled_gaussian(3.0f, s2);
  const HeightField zg1 = convolve_direct(z, g1, s1, s1), zg2 = convolve_direct(z, g2, s2, s2);
  auto combine = [&](float a, float b, float c) {  // a z + b (z*g1) + c (z*g2)
    HeightField o = z;
    for (size_t i = 0; i < o.z.size(); ++i) o.z[i] = a * z.z[i] + b * zg1.z[i] + c * zg2.z[i];
    return from_height(o, 1.0f, true);
  };
  FilterOptions f;
  f.wrap = true;
  f.sigma = 1.5f, f.sigma2 = 3.0f, f.amount = 0.8f;
  f.kind = FilterKind::Smooth;
  EXPECT_LT(max_angle(filter(n, f), combine(0, 1, 0)), 2e-3);
  f.kind = FilterKind::Sharpen;  // z + a (z - z*g1)
  EXPECT_LT(max_angle(filter(n, f), combine(1.8f, -0.8f, 0)), 2e-3);
  f.kind = FilterKind::Edge;  // z + a (z*g1 - z*g2)
  EXPECT_LT(max_angle(filter(n, f), combine(1, 0.8f, -0.8f)), 2e-3);
  f.kind = FilterKind::Detail;  // z*g1 - z*g2
  EXPECT_LT(max_angle(filter(n, f), combine(0, 1, -1)), 2e-3);
}

TEST(RgbnFilter, GradientScalingGivesNormalsOfScaledHeight) {
  const HeightField z = periodic_field(32, 32, 7);
  const Rgbn n = from_height(z, 1.0f, false);
  for (float k : {0.25f, 2.0f, 3.5f}) {
    FilterOptions f;
    f.kind = FilterKind::Scale;
    f.amount = k;
    EXPECT_LT(max_angle(filter(n, f), from_height(z, k, false)), 1e-3) << k;
  }
}

TEST(RgbnFilter, UnitNormalsAfterEveryOperatorAndConstantFieldsKept) {
  const Rgbn n = from_height(periodic_field(64, 64, 8, 20.0f), 1.0f, false);
  Rgbn tilted(32, 32);
  for (size_t i = 0; i < tilted.size(); ++i) tilted.normal[3 * i] = 0.6f, tilted.normal[3 * i + 2] = 0.8f;
  for (auto kind : {FilterKind::Smooth, FilterKind::Sharpen, FilterKind::Edge, FilterKind::Detail, FilterKind::Scale}) {
    FilterOptions f;
    f.kind = kind;
    f.amount = 2.0f;
    EXPECT_LT(max_norm_error(filter(n, f)), 1e-5) << filter_kind_name(kind);
    if (kind == FilterKind::Smooth || kind == FilterKind::Sharpen || kind == FilterKind::Edge) {
      EXPECT_LT(max_angle(filter(tilted, f), tilted), 1e-3) << filter_kind_name(kind);
    }
  }
  EXPECT_LT(max_norm_error(bilateral(n, {})), 1e-5);
  EXPECT_LT(max_angle(bilateral(tilted, {}), tilted), 1e-3);
}

TEST(RgbnFilter, PixelsOutsideTheBrushAreBitIdentical) {
  const Rgbn n = from_height(periodic_field(64, 48, 9, 10.0f), 1.0f, false);
  const Mask m = disc_mask(64, 48, 30, 20, 10, 3);
  FilterOptions f;
  f.kind = FilterKind::Sharpen;
  f.amount = 3;
  for (const Rgbn& out : {filter(n, f, &m), bilateral(n, {}, &m)}) {
    size_t changed_inside = 0;
    for (size_t i = 0; i < n.size(); ++i) {
      const bool same = std::equal(&n.normal[3 * i], &n.normal[3 * i + 3], &out.normal[3 * i]) &&
                        std::equal(&n.albedo[3 * i], &n.albedo[3 * i + 3], &out.albedo[3 * i]);
      if (m[i] == 0) {
        EXPECT_TRUE(same) << i;
      } else {
        changed_inside += !same;
      }
    }
    EXPECT_GT(changed_inside, 100u);
  }
}

TEST(RgbnFilter, BilateralKeepsACreaseThatTheGaussianRounds) {
  // A roof: two planes meeting at x = 16.
  HeightField z{32, 16, std::vector<float>(32 * 16)};
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x) z.at(x, y) = -0.8f * std::abs(x - 15.5f);
  const Rgbn roof = from_height(z, 1.0f, false);
  BilateralOptions b;
  b.sigma_s = 2, b.sigma_n = 0.05f;
  FilterOptions g;
  g.sigma = 2;
  const Rgbn kept = bilateral(roof, b), rounded = filter(roof, g);
  EXPECT_LT(angle_deg(kept.n(14, 8), roof.n(14, 8)), 0.5);
  EXPECT_GT(angle_deg(rounded.n(14, 8), roof.n(14, 8)), 5.0);
}

TEST(RgbnCurvature, PlaneSphereCylinder) {
  const int S = 96;
  const float r = 60;
  Rgbn plane(S, S), sphere(S, S), cylinder(S, S);
  for (size_t i = 0; i < plane.size(); ++i) plane.normal[3 * i] = 0.3f, plane.normal[3 * i + 2] = std::sqrt(1 - 0.09f);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) {
      const float dx = x - S / 2.0f, dy = S / 2.0f - y;  // y up
      const float zs = std::sqrt(r * r - dx * dx - dy * dy);
      float* n = sphere.n(x, y);
      n[0] = dx / r, n[1] = dy / r, n[2] = zs / r;
      float* c = cylinder.n(x, y);
      c[0] = dx / r, c[1] = 0, c[2] = std::sqrt(r * r - dx * dx) / r;
    }
  const Curvature cp = curvature(plane), cs = curvature(sphere), cc = curvature(cylinder);
  for (int y = 30; y < 66; y += 5)
    for (int x = 30; x < 66; x += 5) {
      const size_t i = size_t(y) * S + x;
      EXPECT_NEAR(cp.K[i], 0, 1e-7);
      EXPECT_NEAR(cp.H[i], 0, 1e-6);
      EXPECT_NEAR(cs.K[i], 1 / (r * r), 0.03 / (r * r));
      EXPECT_NEAR(cs.H[i], 1 / r, 0.02 / r);  // a bump towards the viewer: H > 0
      EXPECT_NEAR(cc.K[i], 0, 1e-7);
      EXPECT_NEAR(cc.H[i], 1 / (2 * r), 0.02 / (2 * r));
    }
}

TEST(RgbnSegment, SplitsTwoPlanesAndTwoColours) {
  HeightField z{40, 20, std::vector<float>(800)};
  for (int y = 0; y < 20; ++y)
    for (int x = 0; x < 40; ++x) z.at(x, y) = -0.8f * std::abs(x - 19.5f);
  Rgbn roof = from_height(z, 1.0f, false);
  SegmentOptions o;
  o.min_size = 41;  // the two crease columns (central differences straddle the ridge) join a side
  o.k = 0.3f;
  const Segmentation s = segment(roof, o);
  EXPECT_EQ(s.count, 2);
  EXPECT_NE(s.labels[10 * 40 + 5], s.labels[10 * 40 + 35]);
  // Colour alone separates a flat field with two albedos when the weight is max.
  Rgbn flat(40, 20);
  for (int y = 0; y < 20; ++y)
    for (int x = 20; x < 40; ++x) flat.a(x, y)[0] = 0.9f;
  o.weight = EdgeWeight::Max;
  EXPECT_EQ(segment(flat, o).count, 2);
  o.weight = EdgeWeight::Min;  // min: the normals agree everywhere, one segment
  EXPECT_EQ(segment(flat, o).count, 1);
}

TEST(RgbnSegment, NoSegmentBelowMinSizeAndEverySegmentConnected) {
  // Noisy colour and relief: without min_size FH leaves many tiny segments.
  const int w = 96, h = 64;
  Rgbn im = from_height(rgbn_test::periodic_field(w, h, 77, 5.0f), 1.0f, true);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (float& a : im.albedo) a = u(rng);
  SegmentOptions o;
  o.k = 0.3f;
  o.min_size = 1;
  const Segmentation raw = segment(im, o);
  std::vector<int> raw_size(raw.count, 0);
  for (int l : raw.labels) raw_size[l]++;
  ASSERT_GT(std::count_if(raw_size.begin(), raw_size.end(), [](int n) { return n < 30; }), 20);
  o.min_size = 30;
  const Segmentation s = segment(im, o);
  std::vector<int> size(s.count, 0);
  for (int l : s.labels) size[l]++;
  for (int l = 0; l < s.count; ++l) EXPECT_GE(size[l], 30) << "segment " << l;
  // Each segment is one 8-connected region (FH merges along grid edges only).
  std::vector<char> seen(s.labels.size(), 0);
  std::vector<int> regions(s.count, 0);
  for (size_t start = 0; start < s.labels.size(); ++start) {
    if (seen[start]) continue;
    regions[s.labels[start]]++;
    std::vector<size_t> stack = {start};
    seen[start] = 1;
    while (!stack.empty()) {
      const size_t p = stack.back();
      stack.pop_back();
      const int x = int(p % w), y = int(p / w);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
          const size_t q = size_t(yy) * w + xx;
          if (!seen[q] && s.labels[q] == s.labels[p]) seen[q] = 1, stack.push_back(q);
        }
    }
  }
  for (int l = 0; l < s.count; ++l) EXPECT_EQ(regions[l], 1) << "segment " << l;
}
