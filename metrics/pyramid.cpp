#include "metrics/pyramid.h"

#include <algorithm>
#include <cmath>

#include "metrics/calibration.h"
#include "metrics/detail.h"

namespace proctex::metrics {

std::vector<float> PyramidMetric::compute(const Analysis& analysis) const {
  std::vector<float> f(feature_size(), 0.0f);
  detail::Plane g{analysis.size, analysis.lightness};
  for (int level = 0; level < kLevels; ++level) {
    detail::Plane blurred = detail::blur5(g);
    float* h = f.data() + level * kBins;
    for (std::size_t i = 0; i < g.v.size(); ++i) {
      const float v = g.v[i] - blurred.v[i];
      float t = std::sqrt(std::min(std::abs(v) / kRange, 1.0f));
      if (v < 0) t = -t;
      // Soft binning between bin centres c_k = -1 + (k + 0.5) * width.
      const float p = (t + 1.0f) * 0.5f * kBins - 0.5f;
      int k = static_cast<int>(std::floor(p));
      const float fr = p - static_cast<float>(k);
      h[std::clamp(k, 0, kBins - 1)] += 1.0f - fr;
      h[std::clamp(k + 1, 0, kBins - 1)] += fr;
    }
    const float inv = 1.0f / static_cast<float>(g.v.size());
    for (int k = 0; k < kBins; ++k) h[k] *= inv;
    g = detail::decimate(blurred);
  }
  return f;
}

double PyramidMetric::distance(std::span<const float> a, std::span<const float> b) const {
  static constexpr double weights[kLevels] = {0.5, 1.0, 1.0, 1.0, 1.0};
  double total = 0, wsum = 0;
  const double width = 2.0 / kBins;
  for (int level = 0; level < kLevels; ++level) {
    double ca = 0, cb = 0, emd = 0;
    for (int k = 0; k < kBins; ++k) {
      ca += a[level * kBins + k];
      cb += b[level * kBins + k];
      emd += std::abs(ca - cb) * width;
    }
    total += weights[level] * emd;
    wsum += weights[level];
  }
  return total / wsum;
}

double PyramidMetric::scale() const { return calibration::kPyramidScale; }

}  // namespace proctex::metrics
