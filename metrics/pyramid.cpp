#include "metrics/pyramid.h"

#include <algorithm>
#include <cmath>

#include "metrics/calibration.h"
#include "metrics/detail.h"

namespace proctex::metrics {

std::vector<float> PyramidMetric::compute(const Analysis& analysis) const {
  std::vector<float> f(feature_size(), 0.0f);
  detail::Plane g{analysis.size, analysis.lightness};
  std::vector<float> pos(g.v.size());
  for (int level = 0; level < kLevels; ++level) {
    detail::Plane blurred = detail::blur5(g);
    const std::size_t n = g.v.size();
    // Bin position of every band value (a vectorised pass), then the scatter (a scalar pass).
    // Soft binning between bin centres c_k = -1 + (k + 0.5) * width: position p in [-0.5, kBins
    // - 0.5], bins k = floor(p) and k + 1 with weights 1 - (p - k) and p - k.
    const float* gv = g.v.data();
    const float* bv = blurred.v.data();
    float* pp = pos.data();
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i) {
      const float v = gv[i] - bv[i];
      const float t = std::copysign(std::sqrt(std::min(std::abs(v) / kRange, 1.0f)), v);
      pp[i] = (t + 1.0f) * 0.5f * kBins - 0.5f;
    }
    float* h = f.data() + level * kBins;
    for (std::size_t i = 0; i < n; ++i) {
      const float p = pp[i];
      const int k = static_cast<int>(std::floor(p));
      const float fr = p - static_cast<float>(k);
      h[std::clamp(k, 0, kBins - 1)] += 1.0f - fr;
      h[std::clamp(k + 1, 0, kBins - 1)] += fr;
    }
    const float inv = 1.0f / static_cast<float>(n);
    for (int k = 0; k < kBins; ++k) h[k] *= inv;
    g = detail::decimate(blurred);
  }
  return f;
}

// Weighted mean of the per-level EMDs of group_distances (one definition of a level's distance).
double PyramidMetric::distance(std::span<const float> a, std::span<const float> b) const {
  static constexpr double weights[kLevels] = {0.5, 1.0, 1.0, 1.0, 1.0};
  double emd[kLevels];
  group_distances(a, b, emd);
  double total = 0, wsum = 0;
  for (int level = 0; level < kLevels; ++level) {
    total += weights[level] * emd[level];
    wsum += weights[level];
  }
  return total / wsum;
}

std::size_t PyramidMetric::group_count() const { return kLevels; }

std::string PyramidMetric::group_name(std::size_t group) const {
  return "pyramid.level" + std::to_string(group);
}

void PyramidMetric::group_distances(std::span<const float> a, std::span<const float> b, double* out) const {
  const double width = 2.0 / kBins;
  for (int level = 0; level < kLevels; ++level) {
    double ca = 0, cb = 0, emd = 0;
    for (int k = 0; k < kBins; ++k) {
      ca += a[level * kBins + k];
      cb += b[level * kBins + k];
      emd += std::abs(ca - cb) * width;
    }
    out[level] = emd;
  }
}

double PyramidMetric::scale() const { return calibration::kPyramidScale; }

}  // namespace proctex::metrics
