// Every shader of the library, automatically: valid at defaults, range corners and random interior
// points; deterministic; batch equals single renders; antialiased.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"
#include "image/image.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"

namespace proctex {
namespace {

struct Stats {
  bool finite = true;
  double min_luma = 1e9, max_luma = -1e9, stddev = 0;
  double range = 0;  // largest per-channel max - min: two colours of equal luminance still differ
};

Stats stats(const Image& img) {
  Stats s;
  double sum = 0, sum2 = 0;
  for (size_t i = 0; i < img.pixels.size(); i += 3) {
    const float* p = &img.pixels[i];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) s.finite = false;
    const double l = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    s.min_luma = std::min(s.min_luma, l);
    s.max_luma = std::max(s.max_luma, l);
    sum += l;
    sum2 += l * l;
  }
  for (int c = 0; c < 3; ++c) {
    float lo = 1e9f, hi = -1e9f;
    for (size_t i = c; i < img.pixels.size(); i += 3) {
      lo = std::min(lo, img.pixels[i]);
      hi = std::max(hi, img.pixels[i]);
    }
    s.range = std::max(s.range, double(hi - lo));
  }
  const double n = img.pixels.size() / 3.0;
  s.stddev = std::sqrt(std::max(0.0, sum2 / n - (sum / n) * (sum / n)));
  return s;
}

std::string describe(const ShaderDecl& d, const std::vector<float>& packed) {
  return spec_from_packed(d, packed, 0).to_json().dump();
}

// Parameter vectors that probe the declared ranges. Colours stay at their defaults in the joint
// corners (all colours at 0 would make any shader constant) and are probed one at a time.
std::vector<std::vector<float>> corner_vectors(const ShaderDecl& d) {
  std::vector<std::vector<float>> out = {d.default_packed()};
  auto lo = d.default_packed(), hi = d.default_packed();
  for (const auto& p : d.params) {
    if (p.type == ParamType::Color) continue;
    lo[p.offset] = p.min;
    hi[p.offset] = p.type == ParamType::Bool ? 1.0f : p.max;
  }
  out.push_back(lo);
  out.push_back(hi);
  for (const auto& p : d.params) {
    for (float v : {p.min, p.type == ParamType::Bool ? 1.0f : p.max}) {
      auto x = d.default_packed();
      for (int c = 0; c < p.width(); ++c) x[p.offset + c] = v;
      out.push_back(x);
    }
  }
  return out;
}

std::vector<std::vector<float>> random_vectors(const ShaderDecl& d, int count) {
  // All parameters, fixed ones included: every point of every declared range must render.
  ShaderDecl all = d;
  for (auto& p : all.params) p.searchable = true;
  const ParameterSpace space(all);
  std::mt19937 rng(12345);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<std::vector<float>> out;
  for (int i = 0; i < count; ++i) {
    std::vector<double> x(space.dimensions());
    for (auto& v : x) v = u(rng);
    out.push_back(space.to_packed(x));
  }
  return out;
}

// RGB RMS difference of two renders of one size.
double rms_difference(const Image& a, const Image& b) {
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) sum += std::pow(double(a.pixels[i] - b.pixels[i]), 2);
  return std::sqrt(sum / a.pixels.size());
}

class EveryShader : public ::testing::TestWithParam<std::string> {
 protected:
  const ShaderDecl& decl() const { return ShaderLibrary::builtin().get(GetParam()); }
  Renderer renderer;
};

TEST_P(EveryShader, DeclarationIsComplete) {
  const ShaderDecl& d = decl();
  EXPECT_FALSE(d.help.empty());
  EXPECT_FALSE(d.params.empty()) << "a shader without parameters cannot be matched";
  for (const auto& p : d.params) EXPECT_FALSE(p.help.empty()) << p.name;
}

TEST_P(EveryShader, CornersAndRandomPointsRenderValidNonConstantImages) {
  const ShaderDecl& d = decl();
  auto vectors = corner_vectors(d);
  const size_t corners = vectors.size();
  for (auto& v : random_vectors(d, 8)) vectors.push_back(v);
  const std::vector<uint32_t> seeds(vectors.size(), 3);
  RenderSettings s;
  s.width = s.height = 128;
  const auto images = renderer.render_batch(d, vectors, seeds, s);
  for (size_t i = 0; i < images.size(); ++i) {
    const Stats st = stats(images[i]);
    ASSERT_TRUE(st.finite) << "NaN/Inf at " << describe(d, vectors[i]);
    EXPECT_GE(st.min_luma, -1e-3) << "negative colour at " << describe(d, vectors[i]);
    EXPECT_LE(st.max_luma, 1.5) << "far too bright at " << describe(d, vectors[i]);
    // A degenerate image is (nearly) constant; one colour corner may legitimately lower contrast.
    const bool colour_probe = i >= 3 && i < corners;
    EXPECT_GT(st.range, colour_probe ? 1e-3 : 0.01) << "constant image at " << describe(d, vectors[i]);
  }
}

TEST_P(EveryShader, SameSpecRendersIdenticalPixels) {
  const ShaderDecl& d = decl();
  TextureSpec spec;
  spec.shader = d.name;
  spec.seed = 17;
  RenderSettings s;
  s.width = s.height = 96;
  const Image a = renderer.render(spec, s);
  const Image b = renderer.render(spec, s);
  EXPECT_EQ(a.pixels, b.pixels);
}

TEST_P(EveryShader, BatchRenderEqualsSingleRenders) {
  const ShaderDecl& d = decl();
  const auto vectors = random_vectors(d, 3);
  const std::vector<uint32_t> seeds = {1, 2, 3};
  RenderSettings s;
  s.width = s.height = 64;
  const auto batch = renderer.render_batch(d, vectors, seeds, s);
  for (size_t i = 0; i < vectors.size(); ++i) {
    const auto single = renderer.render_batch(d, {vectors[i]}, {seeds[i]}, s);
    EXPECT_EQ(batch[i].pixels, single[0].pixels) << "sample " << i;
  }
}

// A declared symmetry period (shader.h `period=`) is a promise the matcher and the evaluation rely
// on: the value v and v + period render the same image. Checked at random points of every shader
// that declares one (the star: 360/points), and the control: half a period is another image.
TEST_P(EveryShader, DeclaredSymmetryPeriodsRenderTheSameImage) {
  const ShaderDecl& d = decl();
  RenderSettings s;
  s.width = s.height = 128;
  for (const auto& p : d.params) {
    if (!(p.period > 0.0f)) continue;
    int checked = 0;
    for (auto packed : random_vectors(d, 12)) {
      const double period = symmetry_period(d, p, packed);
      ASSERT_GT(period, 0.0) << p.name << " at " << describe(d, packed);
      if (p.min + period > p.max) continue;  // no two values a period apart in the range
      // v in [min, max - period], so that v + period is inside the range too
      packed[p.offset] = static_cast<float>(p.min + (packed[p.offset] - p.min) / (p.max - p.min) * (p.max - p.min - period));
      auto turned = packed, half = packed;
      turned[p.offset] = static_cast<float>(packed[p.offset] + period);
      half[p.offset] = static_cast<float>(packed[p.offset] + 0.5 * period);
      const auto images = renderer.render_batch(d, {packed, turned, half}, {3u, 3u, 3u}, s);
      // RGB RMS differences (single-precision angles move an edge pixel's coverage by a few 1e-3)
      const double same = rms_difference(images[0], images[1]), other = rms_difference(images[0], images[2]);
      std::printf("%s %s: period %.3f, RMS %.2e, half a period %.2e\n", d.name.c_str(), p.name.c_str(), period, same, other);
      // a tenth of the matcher's pixel-exact limit (search/match.h kPixelExactRmse, 0.005); the
      // hard edges of a 7-pointed star turned by 51.4 degrees measured 1.8e-4
      EXPECT_LT(same, 5e-4) << p.name << " + " << period << " at " << describe(d, packed);
      EXPECT_GT(other, std::max(0.005, 20 * same)) << p.name << " + half a period looks the same at " << describe(d, packed);
      ++checked;
    }
    EXPECT_GE(checked, 6) << p.name;
  }
}

// A declared exchange (shader.h `exchange=A/B`) is the pixel polish's promise (search/pixel_polish.cpp
// carries a point stuck at one end of the range to the other): min with (A, B) renders as max with
// (B, A). Checked at random points of every shader that declares one (the rectangle and the
// superellipse: 0 degrees is 90 with width and height exchanged), and the control: max without
// the exchange is another image (A and B kept apart so it is).
TEST_P(EveryShader, DeclaredExchangesRenderTheSameImage) {
  const ShaderDecl& d = decl();
  RenderSettings s;
  s.width = s.height = 128;
  for (const auto& p : d.params) {
    if (p.exchange.empty()) continue;
    const ParamDecl& a = *d.find(p.exchange[0]);
    const ParamDecl& b = *d.find(p.exchange[1]);
    for (auto packed : random_vectors(d, 6)) {
      packed[p.offset] = p.min;
      packed[a.offset] = a.min + 0.3f * (a.max - a.min);
      packed[b.offset] = a.min + 0.8f * (a.max - a.min);
      auto exchanged = packed, unexchanged = packed;
      exchanged[p.offset] = unexchanged[p.offset] = p.max;
      std::swap(exchanged[a.offset], exchanged[b.offset]);
      const auto images = renderer.render_batch(d, {packed, exchanged, unexchanged}, {3u, 3u, 3u}, s);
      const double same = rms_difference(images[0], images[1]), other = rms_difference(images[0], images[2]);
      EXPECT_LT(same, 5e-4) << p.name << " at its ends, " << a.name << "/" << b.name << " exchanged, at " << describe(d, packed);
      EXPECT_GT(other, std::max(0.005, 20 * same)) << p.name << " at its ends without the exchange looks the same at "
                                                  << describe(d, packed);
    }
  }
}

// A declared dependency holds: with its gate at the minimum the parameter changes nothing, and
// with the gate on it does somewhere (the search scans the two jointly because of it, and an answer
// reports it at its default while the gate is off).
TEST_P(EveryShader, DeclaredDependenciesDoNothingWhileTheGateIsOff) {
  const ShaderDecl& d = decl();
  RenderSettings s;
  s.width = s.height = 128;
  for (const auto& p : d.params) {
    if (p.needs.empty()) continue;
    const ParamDecl& gate = *d.find(p.needs);
    int differs_on = 0;
    for (auto packed : random_vectors(d, 6)) {
      const auto value_at = [&](float share) {  // an int at a whole value
        const float v = p.min + share * (p.max - p.min);
        return p.type == proctex::ParamType::Int ? std::round(v) : v;
      };
      packed[gate.offset] = gate.min;
      packed[p.offset] = value_at(0.2f);
      auto moved = packed;
      moved[p.offset] = value_at(0.7f);
      auto on = packed, on_moved = moved;
      on[gate.offset] = on_moved[gate.offset] = gate.min + 0.5f * (gate.max - gate.min);
      const auto images = renderer.render_batch(d, {packed, moved, on, on_moved}, {3u, 3u, 3u, 3u}, s);
      EXPECT_LT(rms_difference(images[0], images[1]), 1e-5) << p.name << " moved with " << gate.name << " off, at "
                                                            << describe(d, packed);
      if (rms_difference(images[2], images[3]) > 0.005) ++differs_on;
    }
    // Not at every point (a grid's minor width also needs subdivisions > 1), but somewhere.
    EXPECT_GT(differs_on, 0) << p.name << " changed nothing with " << gate.name << " on at 6 random points";
  }
}

// Mean absolute difference in sRGB units between a 256^2 render and a 1024^2 render box-reduced to
// 256^2 (the reference: 16 samples per pixel). Tolerance 0.02 = about 5 of 255 sRGB levels on
// average: invisible in side-by-side viewing, while point-sampled edges and noise octaves finer
// than a pixel (the aliasing this guards against) give 0.05-0.15 on the shaders that have them.
double antialias_error(Renderer& renderer, const TextureSpec& spec, float filter) {
  RenderSettings small;
  small.width = small.height = 256;
  small.filter = filter;
  RenderSettings big = small;
  big.width = big.height = 1024;
  big.filter = 1.0f;
  const Image a = renderer.render(spec, small);
  const Image b = resize(renderer.render(spec, big), 256, 256);
  double sum = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i)
    sum += std::fabs(linear_to_srgb(std::clamp(a.pixels[i], 0.0f, 1.0f)) - linear_to_srgb(std::clamp(b.pixels[i], 0.0f, 1.0f)));
  return sum / a.pixels.size();
}

constexpr double kAntialiasTolerance = 0.02;

TEST_P(EveryShader, AntialiasedRenderAgreesWithSupersampledReference) {
  TextureSpec spec;
  spec.shader = GetParam();
  spec.seed = 5;
  EXPECT_LT(antialias_error(renderer, spec, 1.0f), kAntialiasTolerance);
}

TEST(Antialiasing, PointSampledFineCheckerFailsTheTolerance) {
  // The control: without filtering, a fine checker aliases far beyond the tolerance, so the
  // per-shader test above can fail.
  Renderer renderer;
  const TextureSpec spec = parse_spec_argument("checker:squares=61");
  EXPECT_GT(antialias_error(renderer, spec, 0.0f), 2 * kAntialiasTolerance);
  EXPECT_LT(antialias_error(renderer, spec, 1.0f), kAntialiasTolerance);
}

INSTANTIATE_TEST_SUITE_P(Library, EveryShader, ::testing::ValuesIn(ShaderLibrary::builtin().names()),
                         [](const auto& info) { return info.param; });

TEST(Library, HasTheFirstLibrary) {
  const auto& lib = ShaderLibrary::builtin();
  EXPECT_GE(lib.shaders().size(), 12u);
  for (const char* name : {"bricks", "tiles", "checker", "wood", "marble", "clouds", "starfield", "stones",
                           "polkadots", "rectangle", "circle", "superellipse", "star"})
    EXPECT_NE(lib.find(name), nullptr) << name;
  const ShaderDecl* star = lib.find("star");
  ASSERT_NE(star, nullptr);
  bool integer_points = false;
  for (const auto& p : star->params) integer_points |= p.type == ParamType::Int;
  EXPECT_TRUE(integer_points) << "the star's point count must be an integer parameter";
}

TEST(Library, UnknownShaderSuggestsCloseNames) {
  try {
    ShaderLibrary::builtin().get("chcker");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(e.hint().find("checker"), std::string::npos) << e.hint();
  }
}

TEST(Renderer, RejectsAbsurdSizesBeforeAllocating) {
  Renderer renderer;
  RenderSettings s;
  s.width = s.height = 100000;
  EXPECT_THROW(renderer.render(parse_spec_argument("checker"), s), Error);
  s.width = s.height = 64;
  s.supersample = 0;
  EXPECT_THROW(renderer.render(parse_spec_argument("checker"), s), UsageError);
}

TEST(Renderer, TiledLargeRenderMatchesItsTopRows) {
  // A 4096x4096 render goes in several row tiles; its rows must equal those of an untiled render
  // of the same window (the first 64 rows rendered alone).
  Renderer renderer;
  const TextureSpec spec = parse_spec_argument("checker:squares=13");
  RenderSettings big;
  big.width = big.height = 4096;
  const Image whole = renderer.render(spec, big);
  RenderSettings strip = big;
  strip.height = 64;
  strip.extent = big.extent * 64.0f / 4096.0f;
  const Image top = renderer.render(spec, strip);
  for (int y = 0; y < 64; y += 7)
    for (int x = 0; x < 4096; x += 13)
      ASSERT_NEAR(whole.pixel(x, y)[0], top.pixel(x, y)[0], 1e-5f) << x << "," << y;
}

}  // namespace
}  // namespace proctex
