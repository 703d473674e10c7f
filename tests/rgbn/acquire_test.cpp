// Photometric stereo, PTMs and normal-map MIP filtering on rendered data with known truth.
#include <gtest/gtest.h>

#include "core/error.h"
#include "rgbn/acquire.h"
#include "rgbn/mip.h"
#include "rgbn/view.h"
#include "support.h"

using namespace proctex::rgbn;
using namespace rgbn_test;
using proctex::Image;

namespace {

std::vector<Vec3> ring_of_lights(int n, float elevation, float offset = 0) {
  std::vector<Vec3> l;
  for (int i = 0; i < n; ++i) l.push_back(light_direction(offset + 360.0f * i / n, elevation));
  return l;
}

// Lambertian renders (albedo * max(0, n.l)), optionally with cast shadows marched over `z`.
std::vector<Image> render(const Rgbn& truth, const std::vector<Vec3>& lights, const HeightField* z = nullptr) {
  std::vector<Image> out;
  for (const auto& l : lights) {
    Image img(truth.width, truth.height);
    const float lxy = std::hypot(l[0], l[1]);
    for (int y = 0; y < truth.height; ++y)
      for (int x = 0; x < truth.width; ++x) {
        const float* n = truth.n(x, y);
        float d = std::max(0.0f, n[0] * l[0] + n[1] * l[1] + n[2] * l[2]);
        if (z && lxy > 1e-6f) {
          const float dx = l[0] / lxy, dy = -l[1] / lxy, rise = l[2] / lxy;  // rows grow downwards
          for (float t = 1; t < 64; t += 0.5f) {
            const int xx = int(std::lround(x + dx * t)), yy = int(std::lround(y + dy * t));
            if (xx < 0 || yy < 0 || xx >= truth.width || yy >= truth.height) break;
            if (z->at(xx, yy) > z->at(x, y) + rise * t) {
              d = 0;
              break;
            }
          }
        }
        for (int c = 0; c < 3; ++c) img.pixel(x, y)[c] = truth.a(x, y)[c] * d;
      }
    out.push_back(img);
  }
  return out;
}

double mean_angle(const Rgbn& a, const Rgbn& b, int margin = 0) {
  double s = 0;
  size_t n = 0;
  for (int y = margin; y < a.height - margin; ++y)
    for (int x = margin; x < a.width - margin; ++x) s += angle_deg(a.n(x, y), b.n(x, y)), ++n;
  return s / double(n);
}

void colour_albedo(Rgbn& r) {
  for (int y = 0; y < r.height; ++y)
    for (int x = 0; x < r.width; ++x) {
      float* a = r.a(x, y);
      a[0] = 0.3f + 0.5f * x / r.width, a[1] = 0.6f, a[2] = 0.2f + 0.6f * y / r.height;
    }
}

Rgbn sphere_cap(int S, float R, float rho) {
  Rgbn r(S, S);
  for (int y = 0; y < S; ++y)
    for (int x = 0; x < S; ++x) {
      float dx = x - S / 2.0f, dy = S / 2.0f - y;
      const float d = std::hypot(dx, dy);
      if (d > rho) dx *= rho / d, dy *= rho / d;  // flat beyond the cap's rim would crease; keep its tilt
      const float z = std::sqrt(R * R - dx * dx - dy * dy);
      r.n(x, y)[0] = dx / R, r.n(x, y)[1] = dy / R, r.n(x, y)[2] = z / R;
    }
  colour_albedo(r);
  return r;
}

}  // namespace

TEST(RgbnStereo, LeastSquaresRecoversSphereAndBumpsWithinOneDegree) {
  const std::vector<Vec3> lights = ring_of_lights(6, 60, 10);
  const Rgbn sphere = sphere_cap(64, 60, 40);
  HeightField z = periodic_field(64, 64, 21, 4.0f);
  Rgbn bumps = from_height(z, 1.0f, true);
  colour_albedo(bumps);
  for (const Rgbn* truth : std::vector<const Rgbn*>{&sphere, &bumps}) {
    StereoReport rep;
    const Rgbn got = photometric_stereo(render(*truth, lights), lights, {}, &rep);
    EXPECT_LT(mean_angle(got, *truth), 1.0);
    EXPECT_LT(max_norm_error(got), 1e-5);
    double worst = 0;
    for (size_t i = 0; i < got.albedo.size(); ++i) worst = std::max(worst, double(std::abs(got.albedo[i] - truth->albedo[i])));
    EXPECT_LT(worst, 1e-3);
  }
}

TEST(RgbnStereo, RobustVariantIgnoresCastShadowsWithinThreeDegrees) {
  HeightField z = periodic_field(64, 64, 22, 6.0f);
  Rgbn truth = from_height(z, 1.0f, true);
  colour_albedo(truth);
  const std::vector<Vec3> lights = ring_of_lights(8, 40, 5);
  const std::vector<Image> photos = render(truth, lights, &z);
  StereoOptions robust;
  robust.robust = true;
  StereoReport rr;
  const Rgbn plain = photometric_stereo(photos, lights);
  const Rgbn rob = photometric_stereo(photos, lights, robust, &rr);
  const double e_plain = mean_angle(plain, truth, 2), e_rob = mean_angle(rob, truth, 2);
  EXPECT_LT(e_rob, 3.0);
  EXPECT_LT(e_rob, e_plain);
  EXPECT_GT(rr.samples_dropped, 0.01);
}

TEST(RgbnStereo, BadInputsAreClearErrors) {
  const Rgbn t = sphere_cap(16, 20, 10);
  const auto lights = ring_of_lights(4, 50);
  auto photos = render(t, lights);
  EXPECT_THROW(photometric_stereo({photos[0], photos[1]}, {lights[0], lights[1]}), proctex::UsageError);
  EXPECT_THROW(photometric_stereo(photos, {lights[0], lights[1], lights[2]}), proctex::UsageError);
  // Three lights in one plane through the origin.
  const std::vector<Vec3> flat = {Vec3{1, 0, 0}, Vec3{0, 0, 1}, Vec3{0.70710678f, 0, 0.70710678f}};
  EXPECT_THROW(photometric_stereo({photos[0], photos[1], photos[2]}, flat), proctex::Error);
  photos[2] = Image(8, 8);
  EXPECT_THROW(photometric_stereo(photos, lights), proctex::Error);
}

TEST(RgbnPtm, FitRecoversBiquadraticDataAndRelightingIsLinear) {
  const int w = 12, h = 10;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1, 1);
  Ptm truth{w, h, std::vector<float>(size_t(w) * h * 18)};
  for (float& c : truth.coeff) c = u(rng);
  std::vector<Vec3> lights;
  for (float el : {30.0f, 55.0f, 80.0f})
    for (int k = 0; k < 4; ++k) lights.push_back(light_direction(90.0f * k + el, el));
  std::vector<Image> photos;
  for (const auto& l : lights) photos.push_back(render_ptm(truth, l));
  PtmReport rep;
  const Ptm fit = fit_ptm(photos, lights, &rep);
  double worst = 0;
  for (size_t i = 0; i < fit.coeff.size(); ++i) worst = std::max(worst, double(std::abs(fit.coeff[i] - truth.coeff[i])));
  EXPECT_LT(worst, 1e-4);
  EXPECT_LT(rep.rms_residual, 1e-5);
  // relight(blend) == blend(relight)
  Ptm other = truth;
  for (float& c : other.coeff) c = u(rng);
  const Vec3 l = light_direction(200, 40);
  const Image a = render_ptm(truth, l), b = render_ptm(other, l), ab = render_ptm(blend(truth, other, 0.3f), l);
  for (size_t i = 0; i < ab.pixels.size(); ++i) EXPECT_NEAR(ab.pixels[i], 0.7f * a.pixels[i] + 0.3f * b.pixels[i], 1e-5);
  // Orthonormal basis: Legendre distance is the L2 distance of the functions on [-1,1]^2 (/2).
  const float* pa = truth.at(3, 4, 0);
  const float* pb = other.at(3, 4, 0);
  const auto la = legendre(pa), lb = legendre(pb);
  double dl = 0;
  for (int k = 0; k < 6; ++k) dl += (la[k] - lb[k]) * (la[k] - lb[k]);
  double df = 0;
  const int N = 400;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) {
      const double uu = -1 + (i + 0.5) * 2 / N, vv = -1 + (j + 0.5) * 2 / N;
      const double b6[6] = {1, uu, vv, uu * vv, uu * uu, vv * vv};
      double d = 0;
      for (int k = 0; k < 6; ++k) d += (pa[k] - pb[k]) * b6[k];
      df += d * d * (4.0 / (N * N));
    }
  EXPECT_NEAR(dl, df, 1e-3 * df);
  // Too few or degenerate lights.
  EXPECT_THROW(fit_ptm({photos.begin(), photos.begin() + 5}, {lights.begin(), lights.begin() + 5}), proctex::UsageError);
  const auto ring = ring_of_lights(8, 45);  // u^2 + v^2 constant: 1, u^2, v^2 are dependent
  std::vector<Image> p8(8, photos[0]);
  EXPECT_THROW(fit_ptm(p8, ring), proctex::Error);
}

TEST(RgbnPtm, SynthesisCopiesExampleFunctionsAndIsDeterministic) {
  Ptm ex{32, 32, std::vector<float>(32 * 32 * 18)};
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> u(0, 1);
  for (float& c : ex.coeff) c = u(rng);
  const Ptm a = synthesize_ptm(ex, 60, 50, 12, 3), b = synthesize_ptm(ex, 60, 50, 12, 3);
  EXPECT_EQ(a.coeff, b.coeff);
  EXPECT_NE(a.coeff, synthesize_ptm(ex, 60, 50, 12, 4).coeff);
  // Pixel (0,0) lies in the first patch only: an exact copy of some example pixel.
  bool found = false;
  for (int y = 0; y < 32 && !found; ++y)
    for (int x = 0; x < 32 && !found; ++x) found = std::equal(a.at(0, 0, 0), a.at(0, 0, 0) + 18, ex.at(x, y, 0));
  EXPECT_TRUE(found);
}

namespace {
// Faceted normals: every texel takes one of three facets (25 degrees tilt) at random, so a
// footprint of 2-8 texels holds several distinct normal modes.
Rgbn facets(int S, unsigned seed) {
  std::mt19937 rng(seed);
  Rgbn r(S, S);
  for (size_t i = 0; i < r.size(); ++i) {
    const int k = int(rng() % 3);
    const Vec3 n = light_direction(120.0f * k + 15.0f, 65.0f);
    std::copy(n.begin(), n.end(), &r.normal[3 * i]);
  }
  return r;
}
}  // namespace

TEST(RgbnMip, VmfMixtureBeatsToksvigOnMultiModalFootprints) {
  const Rgbn fine = facets(64, 31);
  MipOptions o;
  for (int f : {2, 4, 8}) {
    const MipLevel L = build_level(fine, f, o, true, false);
    for (float s : {8.0f, 32.0f, 128.0f}) {
      const double et = mip_error(fine, L, MipMethod::Toksvig, s), ev = mip_error(fine, L, MipMethod::Vmf, s);
      const double en = mip_error(fine, L, MipMethod::Naive, s);
      EXPECT_LE(ev, 0.7 * et) << "footprint " << f << " exponent " << s;
      EXPECT_LT(et, en) << "footprint " << f << " exponent " << s;
    }
  }
}

TEST(RgbnMip, FootprintOneIsExactAndSmoothMapsKeepVmfNoWorse) {
  const Rgbn fine = from_height(periodic_field(32, 32, 32, 3.0f), 1.0f, true);
  MipOptions o;
  const MipLevel one = build_level(fine, 1, o, true, false);
  for (auto m : {MipMethod::Naive, MipMethod::Toksvig, MipMethod::Vmf}) EXPECT_LT(mip_error(fine, one, m, 32), 1e-4);
  for (int f : {2, 4, 8})
    for (float s : {8.0f, 64.0f}) {
      const MipLevel L = build_level(fine, f, o, true, false);
      EXPECT_LE(mip_error(fine, L, MipMethod::Vmf, s), mip_error(fine, L, MipMethod::Toksvig, s) * 1.001 + 1e-6);
    }
}

// The harder maps of bench_rgbn_mip where 4 lobes fell short (0.70 x Toksvig with six jittered
// facets per texel; 1.04 x on steep smooth bumps at footprint 16, exponent 128): the default
// lobe count must hold the targets there too.
TEST(RgbnMip, DefaultLobesHoldTheTargetsOnSixModesAndSteepBumps) {
  std::mt19937 rng(4);
  std::normal_distribution<float> g(0, 4.0f);
  Rgbn six(64, 64);
  for (size_t i = 0; i < six.size(); ++i) {
    const int k = int(rng() % 6);
    const Vec3 n = light_direction(60.0f * k + 15.0f + 3 * g(rng), 90.0f - (k % 2 ? 35.0f : 15.0f) + g(rng));
    std::copy(n.begin(), n.end(), &six.normal[3 * i]);
  }
  MipOptions o;
  for (int f : {4, 8}) {
    const MipLevel L = build_level(six, f, o, true, false);
    for (float s : {32.0f, 128.0f})
      EXPECT_LE(mip_error(six, L, MipMethod::Vmf, s), 0.7 * mip_error(six, L, MipMethod::Toksvig, s))
          << "footprint " << f << " exponent " << s;
  }
  HeightField z{64, 64, std::vector<float>(64 * 64, 0.0f)};
  std::uniform_real_distribution<float> u(0, 1);
  for (int k = 0; k < 12; ++k) {
    const int fx = 1 + int(u(rng) * 12), fy = int(u(rng) * 12);
    const float ph = u(rng) * 6.28f, a = 20.0f / (fx + fy);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) z.at(x, y) += a * std::sin(6.2831853f * (fx * x + fy * y) / 64.0f + ph);
  }
  const Rgbn bumps = from_height(z, 1.0f, true);
  const MipLevel L = build_level(bumps, 16, o, true, false);
  for (float s : {32.0f, 128.0f})
    EXPECT_LE(mip_error(bumps, L, MipMethod::Vmf, s), mip_error(bumps, L, MipMethod::Toksvig, s)) << "exponent " << s;
}

TEST(RgbnMip, SphericalEmFindsTwoClusters) {
  std::vector<Vec3> ns;
  const Vec3 a = light_direction(0, 60), b = light_direction(180, 70);
  for (int i = 0; i < 30; ++i) ns.push_back(a);
  for (int i = 0; i < 10; ++i) ns.push_back(b);
  const auto lobes = fit_vmf(ns, 4, 12);
  ASSERT_EQ(lobes.size(), 2u);
  const auto& big = lobes[0].alpha > lobes[1].alpha ? lobes[0] : lobes[1];
  EXPECT_NEAR(big.alpha, 0.75, 1e-3);
  EXPECT_LT(angle_deg(big.mu.data(), a.data()), 0.1);
  EXPECT_GT(big.kappa, 1e4);
}

// --- jump maps ---------------------------------------------------------------------------------
#include "rgbn/synth.h"

TEST(RgbnJumpMap, OutputsAreCopiesOfExampleValuesAndRunsAreAboutOneOverP) {
  Rgbn ex = from_height(periodic_field(40, 40, 41, 6.0f), 1.0f, true);
  colour_albedo(ex);
  JumpMapOptions jo;
  const JumpMap map = build_jump_map(ex, jo);
  ASSERT_EQ(map.jumps.size(), ex.size());
  for (const auto& j : map.jumps) EXPECT_EQ(j.size(), 4u);
  for (Order order : {Order::Hilbert, Order::ShuffledDfs}) {
    JumpSynthOptions so;
    so.order = order;
    so.jump_probability = 0.05;
    so.seed = 7;
    const JumpSynthResult r = jump_synthesize(ex, map, 96, 80, so);
    ASSERT_EQ(r.visited, size_t(96 * 80));
    for (size_t p = 0; p < r.image.size(); ++p) {
      const int s = r.source[p];
      ASSERT_GE(s, 0);
      EXPECT_TRUE(std::equal(&r.image.normal[3 * p], &r.image.normal[3 * p + 3], &ex.normal[3 * size_t(s)]));
      EXPECT_TRUE(std::equal(&r.image.albedo[3 * p], &r.image.albedo[3 * p + 3], &ex.albedo[3 * size_t(s)]));
    }
    // Runs end at jumps (probability p) and at the example's border, so the mean is below 1/p
    // but of its order.
    EXPECT_GT(r.mean_run, 4.0);
    EXPECT_LT(r.mean_run, 1.0 / so.jump_probability + 1);
    const JumpSynthResult again = jump_synthesize(ex, map, 96, 80, so);
    EXPECT_EQ(again.source, r.source);
  }
}

TEST(RgbnJumpMap, ShuffledDfsVisitsEveryMaskedPixelOnceAndFillKeepsTheRest) {
  const int w = 50, h = 40;
  std::vector<char> inside(w * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) inside[y * w + x] = std::hypot(x - 20, y - 20) < 12 || (x > 35 && y > 30);
  const auto order = visit_order(w, h, inside, Order::ShuffledDfs, 3);
  std::vector<int> count(w * h, 0);
  for (int p : order) count[p]++;
  for (int i = 0; i < w * h; ++i) EXPECT_EQ(count[i], inside[i] ? 1 : 0);
  const auto hil = visit_order(w, h, inside, Order::Hilbert, 3);
  EXPECT_EQ(hil.size(), order.size());

  Rgbn ex = from_height(periodic_field(32, 32, 42, 4.0f), 1.0f, true);
  const JumpMap map = build_jump_map(ex);
  Rgbn target = from_height(periodic_field(w, h, 43, 2.0f), 1.0f, false);
  Mask mask(w * h);
  for (int i = 0; i < w * h; ++i) mask[i] = inside[i];
  JumpSynthOptions so;
  so.compose = true;
  so.order = Order::ShuffledDfs;
  const JumpSynthResult r = jump_fill(ex, map, target, mask, so);
  for (int i = 0; i < w * h; ++i) {
    if (!inside[i]) {
        EXPECT_TRUE(std::equal(&target.normal[3 * i], &target.normal[3 * i + 3], &r.image.normal[3 * i]));
      }
  }
  EXPECT_LT(max_norm_error(r.image), 1e-5);
}
