#pragma once
// Acquisition and relighting from photos under known lights:
//  - photometric stereo (Pereira & Velho §1.3): I_i = a <n, l_i>, least squares over >= 3 lights;
//  - polynomial texture maps (Hel-Or et al.; Malzbender): L(u, v) = [1 u v uv u^2 v^2] . a per
//    pixel and channel, (u, v) = the light direction's x and y.
#include <filesystem>
#include <vector>

#include "image/image.h"
#include "rgbn/rgbn.h"

namespace proctex::rgbn {

struct StereoOptions {
  bool robust = false;
  // Robust variant: samples darker than `shadow` times the pixel's brightest sample are taken as
  // shadowed; after a fit, samples brighter than the Lambert prediction by more than
  // `specular` times the albedo are taken as highlights and the fit repeated without them.
  float shadow = 0.1f;
  float specular = 0.15f;
};
struct StereoReport {
  double mean_residual = 0;     // RMS of I - a <n, l> over the used samples (grey)
  double samples_dropped = 0;   // fraction of samples the robust variant ignored
  double condition = 0;         // condition number of the light matrix
};
// `photos` (linear RGB, same size) lit from unit directions `lights` (towards the light).
// Throws for mismatched sizes, fewer than 3 lights, or (nearly) coplanar light directions.
Rgbn photometric_stereo(const std::vector<Image>& photos, const std::vector<Vec3>& lights,
                        const StereoOptions& options = {}, StereoReport* report = nullptr);

// --- PTM ---------------------------------------------------------------------------------------
struct Ptm {
  int width = 0;
  int height = 0;
  std::vector<float> coeff;  // per pixel, per channel (R, G, B), 6 coefficients a0..a5
  const float* at(int x, int y, int c) const { return &coeff[(size_t(y) * width + x) * 18 + c * 6]; }
  float* at(int x, int y, int c) { return &coeff[(size_t(y) * width + x) * 18 + c * 6]; }
};
struct PtmReport {
  double rms_residual = 0;
  double condition = 0;
};
// Least-squares fit over >= 6 photos; throws for mismatched sizes, too few or degenerate lights.
Ptm fit_ptm(const std::vector<Image>& photos, const std::vector<Vec3>& lights, PtmReport* report = nullptr);
// Evaluates the polynomial at the light's (u, v) = (l_x, l_y) (no clamping: linear in the PTM).
Image render_ptm(const Ptm& ptm, const Vec3& light);
// Blend (1 - t) a + t b of two PTMs of the same size.
Ptm blend(const Ptm& a, const Ptm& b, float t);
// Orthonormal 2-D Legendre coefficients on [-1,1]^2 (Hel-Or): distance between b vectors equals
// the L2 distance between the reflectance functions (up to a constant factor).
std::array<float, 6> legendre(const float* a);
// Synthesises a w x h PTM that looks like the example under every light: patch quilting (patch
// `patch` pixels, overlap patch/6) choosing each patch by the overlap's distance in the Legendre
// basis among the best candidates, alpha-blended overlaps; deterministic for a seed.
Ptm synthesize_ptm(const Ptm& example, int w, int h, int patch, uint64_t seed);

// EXR with 18 float channels R.a0..B.a5.
void save_ptm(const Ptm& ptm, const std::filesystem::path& path);
Ptm load_ptm(const std::filesystem::path& path);

}  // namespace proctex::rgbn
