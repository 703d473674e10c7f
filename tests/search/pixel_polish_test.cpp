// The pixel polish (search/pixel_polish.h) as proctex match relies on it for deterministic
// patterns: from a point that renders nearly the target, every continuous parameter comes back
// to within 2% of its range (issue 12's criterion), and swapped colours hidden by a shift are
// undone. Real renders through PoCL.
#include <gtest/gtest.h>

#include <cmath>

#include "search/pixel_polish.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"
#include "shaders/spec.h"

namespace proctex::search {
namespace {

struct Case {
  const ShaderDecl* decl;
  std::vector<float> truth;
};

Case make(const std::string& spec_text) {
  const auto& lib = ShaderLibrary::builtin();
  const TextureSpec spec = parse_spec_argument(spec_text);
  const ShaderDecl& decl = lib.get(spec.shader);
  return {&decl, resolve(decl, spec)};
}

Image render(Renderer& r, const Case& c, const std::vector<float>& packed) {
  RenderSettings s;
  s.width = s.height = 256;
  return r.render_batch(*c.decl, {packed}, std::vector<uint32_t>{1u}, s).front();
}

// Largest |difference| over the continuous parameters, as a share of each one's range.
double worst_unit_error(const Case& c, const std::vector<float>& packed) {
  const ParameterSpace space(*c.decl);
  const auto a = space.to_unit(packed), b = space.to_unit(c.truth);
  double worst = 0;
  for (size_t d = 0; d < a.size(); ++d)
    if (!space.dims()[d].levels) worst = std::max(worst, std::fabs(a[d] - b[d]));
  return worst;
}

void set(const Case& c, std::vector<float>& packed, const std::string& name, std::vector<float> value) {
  const ParamDecl* p = c.decl->find(name);
  ASSERT_NE(p, nullptr) << name;
  for (size_t i = 0; i < value.size(); ++i) packed[p->offset + i] = value[i];
}

// The polish does not pretend (rmse < 0) from `start`, and spends only the registrations and, at
// the origin, one least-squares colour fit per start (its two colours + 1 renders).
void expect_left_alone(Renderer& renderer, const Case& c, const Image& target, const std::vector<float>& start) {
  nlohmann::json report;
  const auto r = pixel_polish(*c.decl, start, 1u, {}, target, renderer, kPixelPolishBudget, report);
  EXPECT_LT(r.rmse, 0.0) << report.dump();
  EXPECT_LE(r.evaluations, 3 * (1 + 3)) << report.dump();
}

// The polish from `start` comes back to the truth: pixels within RMS 0.001 at no shift, every
// parameter within 2% of its range.
void expect_polished_to_truth(Renderer& renderer, const Case& c, const Image& target, const std::vector<float>& start) {
  nlohmann::json report;
  const auto r = pixel_polish(*c.decl, start, 1u, {}, target, renderer, kPixelPolishBudget, report);
  ASSERT_GE(r.rmse, 0.0) << report.dump();
  EXPECT_LT(r.rmse, 1e-3) << report.dump();
  EXPECT_LT(worst_unit_error(c, r.packed), 0.02) << report.dump();
  EXPECT_EQ(r.dx, 0);
  EXPECT_EQ(r.dy, 0);
}

}  // namespace

TEST(PixelPolish, SoftnessTradedAgainstDutyAndColourComesBackExact) {
  // A 15-arm swirl: softness, duty and a colour off by 4-6% of their ranges render within a few
  // thousandths RMS of the target (the case the statistics could not resolve).
  Renderer renderer;
  const Case c = make("swirl:arms=15,twist=11.1,duty=0.85,softness=0.75,color_a=(0.13,0.18,0.74),color_b=(0.78,0.39,0.1)");
  const Image target = render(renderer, c, c.truth);
  auto start = c.truth;
  set(c, start, "softness", {0.81f});
  set(c, start, "duty", {0.86f});
  set(c, start, "color_b", {0.82f, 0.40f, 0.06f});
  ASSERT_GT(worst_unit_error(c, start), 0.035);
  expect_polished_to_truth(renderer, c, target, start);
}

TEST(PixelPolish, SwappedColoursWithComplementedDutyAreUndone) {
  // Stripes in swapped colours with the complementary duty are the target moved by part of a
  // period: a shifted registration calls that nearly exact, but the parameters are not the
  // target's. The polish tries the swap and keeps the start that lines up without a shift.
  Renderer renderer;
  const Case c = make("stripes:stripes=12,duty=0.35,angle=30,softness=0.3,color_a=(0.7,0.2,0.1),color_b=(0.1,0.3,0.6)");
  const Image target = render(renderer, c, c.truth);
  auto start = c.truth;
  set(c, start, "color_a", {0.1f, 0.3f, 0.6f});
  set(c, start, "color_b", {0.7f, 0.2f, 0.1f});
  set(c, start, "duty", {0.66f});
  set(c, start, "softness", {0.33f});
  nlohmann::json report;
  const auto r = pixel_polish(*c.decl, start, 1u, {}, target, renderer, kPixelPolishBudget, report);
  ASSERT_GE(r.rmse, 0.0) << report.dump();
  EXPECT_LT(r.rmse, 1e-3) << report.dump();
  EXPECT_EQ(r.start, "colours swapped, duty complemented") << report.dump();
  EXPECT_EQ(r.dx, 0);
  EXPECT_EQ(r.dy, 0);
  EXPECT_LT(worst_unit_error(c, r.packed), 0.02) << report.dump();
}

TEST(PixelPolish, DutyAndSoftnessTradedAlongAValleyComeBackExact) {
  // A chevron (a deterministic benchmark target of session 9): duty 0.40 with softness 0.84
  // renders within RMS 0.001 of duty 0.49 with softness 0.46 at a shifted registration, and a
  // local search from there (or from the start moved to the origin) stops short of the truth.
  // Swept across its range, one of the two finds the other side of the trade.
  Renderer renderer;
  const Case c = make("chevron:stripes=30,zigzags=12,amplitude=1.3635,duty=0.4868,softness=0.4619,"
                      "color_a=(0.99,0.64,0.029),color_b=(0.848,0.91,0.386)");
  const Image target = render(renderer, c, c.truth);
  auto start = c.truth;
  set(c, start, "duty", {0.405f});
  set(c, start, "softness", {0.841f});
  set(c, start, "amplitude", {1.361f});
  ASSERT_GT(worst_unit_error(c, start), 0.3);
  expect_polished_to_truth(renderer, c, target, start);
}

TEST(PixelPolish, AFarPointIsLeftAlone) {
  // Nothing lines up: the polish does not pretend (rmse < 0), and spends only the registrations
  // and, at the origin, one least-squares colour fit per start (its two colours + 1 renders).
  Renderer renderer;
  const Case c = make("swirl:arms=5,twist=4,duty=0.5,softness=0.2");
  const Image target = render(renderer, c, c.truth);
  auto start = c.truth;
  set(c, start, "twist", {-12.0f});
  expect_left_alone(renderer, c, target, start);
}

TEST(PixelPolish, OnAFaintTargetAStartNoCloserThanAFlatImageIsLeftAlone) {
  // Dark blue stripes (target 7 of the 18 deterministic benchmark targets): a flat image of the
  // mean colour registers at RMS 0.035, under the absolute start limit (0.05), and so did every
  // wrong finalist (polkadots, chevron, checker: 0.0345). A start there has not lined up: it is
  // not polished (before: 1500 renders each, nothing gained).
  Renderer renderer;
  const Case c = make("stripes:stripes=34,duty=0.1115,angle=135.42,softness=0.534,wave=0.72,wave_frequency=4.079,"
                      "color_a=(0.0374,0.022,0.568),color_b=(0.12,0.1617,0.823)");
  const Image target = render(renderer, c, c.truth);
  ASSERT_LT(flat_rmse(target), kPixelPolishStartRmse);
  auto start = c.truth;
  set(c, start, "stripes", {13.0f});
  set(c, start, "wave", {0.1f});
  expect_left_alone(renderer, c, target, start);
}

TEST(PixelPolish, OnAFaintTargetALinedUpStartIsStillPolished) {
  // The same faint stripes from the right count with the duty and softness off: closer than the
  // flat image, so polished back to the truth.
  Renderer renderer;
  const Case c = make("stripes:stripes=34,duty=0.1115,angle=135.42,softness=0.534,wave=0.72,wave_frequency=4.079,"
                      "color_a=(0.0374,0.022,0.568),color_b=(0.12,0.1617,0.823)");
  const Image target = render(renderer, c, c.truth);
  auto start = c.truth;
  set(c, start, "duty", {0.13f});
  set(c, start, "softness", {0.5f});
  expect_polished_to_truth(renderer, c, target, start);
}

// A small soft ring (session 14, deterministic target 12 of bench_match_eval --targets 18): the
// point the align stage left wants a ring colour with blue above 1 (a ring too thin, made up for
// by contrast). The polish's colour model solved the colours without their range: RMS 1e-5 by
// the model, 0.0033 rendered, and it stopped there (ring 11% and softness 16% of their ranges
// off). With the colours bounded (and the least squares' ridge 1e-12, was 1e-6: a bias of RMS
// 6e-6 on a colour that covers few pixels) it reaches the target's pixels.
//
// Its parameters are not all the target's, and cannot be: when the blur w = fw + softness * size
// is wider than the ring's thickness t, the ring's coverage is a tent of slope 1/w and peak below
// 1 (pt_coverage), so the image fixes only the band's middle radius r - t/2, the tent's half base
// (w + t) / 2 and (fg - bg) / w - every w along that family renders the same image (checked
// below: a member 10% blurrier renders within RMS 1e-5 with the ring 4% of its range away).
// The polish must recover those three, which is what the pixels say.
TEST(PixelPolish, ASoftRingComesBackToTheSameImageAndItsIdentifiableShape) {
  Renderer renderer;
  const Case c = make("circle:size=0.1843,ring=0.6363,softness=0.2987,fg=(0.185,0.1,0.9885),bg=(0.4054,0.4739,0.5626)");
  const Image target = render(renderer, c, c.truth);
  struct Shape {
    double middle, half_base;
    std::vector<double> slope;  // (fg - bg) / w per channel
  };
  const auto param = [&](const std::vector<float>& p, const std::string& name, int channel = 0) {
    return double(p[c.decl->find(name)->offset + channel]);
  };
  const double fw = 1.0 / 256;
  const auto shape_of = [&](const std::vector<float>& p) {
    const double r = 0.5 * param(p, "size"), t = r * (1 - 0.9 * param(p, "ring"));
    const double w = fw + param(p, "softness") * param(p, "size");
    Shape sh{r - t / 2, (w + t) / 2, {}};
    for (int ch = 0; ch < 3; ++ch) sh.slope.push_back((param(p, "fg", ch) - param(p, "bg", ch)) / w);
    return sh;
  };
  const Shape truth = shape_of(c.truth);
  {  // the family: 10% more blur, the same middle, base and slope
    std::vector<float> other = c.truth;
    const double r0 = 0.5 * param(c.truth, "size"), t0 = r0 * (1 - 0.9 * param(c.truth, "ring"));
    const double w = 1.1 * (fw + param(c.truth, "softness") * param(c.truth, "size")), t = 2 * truth.half_base - w;
    ASSERT_GT(w, t0);
    const double r = truth.middle + t / 2;
    set(c, other, "size", {float(2 * r)});
    set(c, other, "ring", {float((1 - t / r) / 0.9)});
    set(c, other, "softness", {float((w - fw) / (2 * r))});
    std::vector<float> fg;
    for (int ch = 0; ch < 3; ++ch) fg.push_back(float(param(c.truth, "bg", ch) + truth.slope[ch] * w));
    set(c, other, "fg", fg);
    const Image same = render(renderer, c, other);
    double sum = 0;
    for (size_t i = 0; i < same.pixels.size(); ++i) sum += std::pow(double(same.pixels[i] - target.pixels[i]), 2);
    EXPECT_LT(std::sqrt(sum / same.pixels.size()), 1e-5);
    EXPECT_GT(std::fabs(param(other, "ring") - param(c.truth, "ring")), 0.03);
  }
  const Case start = make("circle:size=0.1735,ring=0.7447,softness=0.3793,fg=(0.1447,0.0319,1),bg=(0.4054,0.4739,0.5626)");
  nlohmann::json report;
  const auto r = pixel_polish(*c.decl, start.truth, 1u, {}, target, renderer, kPixelPolishBudget, report);
  ASSERT_GE(r.rmse, 0.0) << report.dump();
  EXPECT_LT(r.rmse, 1e-5) << report.dump();  // 0.0033 before
  EXPECT_EQ(r.dx, 0);
  EXPECT_EQ(r.dy, 0);
  const Shape found = shape_of(r.packed);
  EXPECT_NEAR(found.middle, truth.middle, 1e-4) << report.dump();  // texture units (1/256 = a pixel)
  EXPECT_NEAR(found.half_base, truth.half_base, 1e-4) << report.dump();
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(found.slope[ch], truth.slope[ch], 0.01 * std::fabs(truth.slope[ch]) + 0.01) << ch;
}

// Two points the local searches left in the wrong basin (bench_match_eval --targets 18, session 20:
// targets 3 and 17), polished back by the hops between basins (pixel_polish.cpp).
TEST(PixelPolish, ARingPolishedToATentFindsTheFlatTopOfTheTarget) {
  // Blur narrower than the band: the target's ring reaches its colour on a flat top. The start,
  // blurrier and thinner, is a tent whose peak never does; every point on the straight line to
  // the truth is worse (RMS 0.0091 at the start, 0.0091 a third of the way) until the band is
  // wider than the blur.
  Renderer renderer;
  const Case c = make("circle:size=0.902,ring=0.4772,softness=0.2058,fg=(0.9628,0.2018,0.4349),bg=(0.7925,0.6946,0.5372)");
  const Image target = render(renderer, c, c.truth);
  const Case start = make("circle:size=0.857,ring=0.5613,softness=0.2819,fg=(0.9985,0.0985,0.4134),bg=(0.7925,0.6946,0.5372)");
  expect_polished_to_truth(renderer, c, target, start.truth);
}

// Fine wavy stripes (43 across 256 px): the align stage's finest renders are averaged by 2, which
// leaves a 3 px period nearly a sinusoid whatever its duty, so it handed over duty 0.75 and softness
// 1 in swapped colours for the target's 0.42 and 0.2 (match JSON of session 22). At the origin, after
// the colour fit, that start is RMS 0.118 from the target - beyond the 0.1 the polish admitted before
// - and polishes to 0.001.
TEST(PixelPolish, FineStripesWithTheirDutyAndSoftnessUnseenArePolishedFromTheOrigin) {
  Renderer renderer;
  const Case c = make("stripes:stripes=43,angle=81.1469,duty=0.42196,softness=0.20113,wave=0.30271,"
                      "wave_frequency=2.73295,color_a=(0.7211,0.7082,0.0542),color_b=(0.5247,0.2287,0.7181)");
  const Image target = render(renderer, c, c.truth);
  const Case start = make("stripes:stripes=43,angle=81.1484,duty=0.75,softness=1,wave=0.30266,wave_frequency=2.73295,"
                          "color_a=(0.5374,0.2376,0.5811),color_b=(0.8478,1,0)");
  nlohmann::json report;
  const auto r = pixel_polish(*c.decl, start.truth, 1u, {}, target, renderer, kPixelPolishBudget, report);
  ASSERT_GE(r.rmse, 0.0) << report.dump();
  EXPECT_LT(r.rmse, 0.002) << report.dump();
  EXPECT_LT(worst_unit_error(c, r.packed), 0.02) << report.dump();
  EXPECT_EQ(r.dx, 0);
  EXPECT_EQ(r.dy, 0);
}

// A small spiky star (50 px across, 6 points): the polish keeps counts, and a start with 3 points
// (what the match handed over for session 21's synthetic target 43) polished to RMS 0.011 and stayed.
// The count hop tries every other count at 6 phases of its rotation period and finds 6 points.
TEST(PixelPolish, AStarPolishedWithTheWrongCountFindsItsPoints) {
  Renderer renderer;
  const Case c = make("star:points=6,size=0.19674,inner=0.11695,rotation=25.064,softness=0.06059,"
                      "fg=(0.733,0.8273,0.3211),bg=(0.0961,0.6756,0.285)");
  const Image target = render(renderer, c, c.truth);
  const Case start = make("star:points=3,size=0.197,inner=0.123,rotation=145.054,softness=0.063,"
                          "fg=(0.595,0.794,0.313),bg=(0.097,0.676,0.285)");
  nlohmann::json report;
  const auto r = pixel_polish(*c.decl, start.truth, 1u, {}, target, renderer, kPixelPolishBudget, report);
  ASSERT_GE(r.rmse, 0.0) << report.dump();
  EXPECT_EQ(r.packed[c.decl->find("points")->offset], 6.0f) << report.dump();
  EXPECT_LT(r.rmse, 1e-3) << report.dump();
  // The rotation compared modulo its period (60 degrees at 6 points), as the benchmark does.
  const ParamDecl& rotation = *c.decl->find("rotation");
  EXPECT_LT(parameter_difference(*c.decl, rotation, r.packed[rotation.offset], 25.064f, r.packed), 0.02 * 180)
      << report.dump();
  auto canonical = canonical_packed(*c.decl, r.packed);
  EXPECT_LT(worst_unit_error(c, canonical), 0.02) << report.dump();
}

TEST(PixelPolish, ASuperellipseTurnedByHalfItsRangeComesBack) {
  // A diamond-like superellipse (exponent 1.54) turned 52 degrees, found as a squarer one
  // (exponent 3.2) turned 10 degrees: each is the other turned 45 degrees to the eye, RMS 0.046,
  // and no local search crosses from one to the other.
  Renderer renderer;
  const Case c = make("superellipse:exponent=1.5389,height=0.7314,rotation=52.118,softness=0.00316,width=0.7875,"
                      "fg=(0.5514,0.4074,0.1664),bg=(0.8138,0.7016,0.8743)");
  const Image target = render(renderer, c, c.truth);
  const Case start = make("superellipse:exponent=3.1994,height=0.6861,rotation=9.814,softness=0.0025,width=0.6558,"
                          "fg=(0.5475,0.4123,0.1749),bg=(0.817,0.7065,0.8902)");
  expect_polished_to_truth(renderer, c, target, start.truth);
}

TEST(PixelPolish, ASuperellipseStoppedAtTheEndOfItsRotationGoesOnFromTheOtherEnd) {
  // Target 48 of bench_match_eval --targets 53 (session 21): turned 81.7 degrees; found at 0 degrees
  // with its width and height exchanged - the target's neighbour across the end of the rotation's
  // range (0 with width and height exchanged is 90), RMS 0.026, where no local search goes on.
  Renderer renderer;
  const Case c = make("superellipse:exponent=11.44,height=0.3689,rotation=81.679,softness=0.2397,width=0.2523,"
                      "fg=(0.9437,0.4302,0.7443),bg=(0.1091,0.0902,0.2202)");
  const Image target = render(renderer, c, c.truth);
  const Case start = make("superellipse:exponent=5.472,height=0.2548,rotation=0,softness=0.2785,width=0.3709,"
                          "fg=(0.9562,0.4363,0.7547),bg=(0.108,0.0896,0.2191)");
  {  // the declared exchange (shaders/shape/superellipse.cl): 0 degrees is 90 with width and height exchanged
    Case other = start;
    set(other, other.truth, "rotation", {90.0f});
    set(other, other.truth, "width", {0.2548f});
    set(other, other.truth, "height", {0.3709f});
    const Image a = render(renderer, start, start.truth), b = render(renderer, other, other.truth);
    double worst = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) worst = std::max(worst, double(std::fabs(a.pixels[i] - b.pixels[i])));
    EXPECT_LT(worst, 1e-3);
  }
  expect_polished_to_truth(renderer, c, target, start.truth);
}

}  // namespace proctex::search

