#include "metrics/colour.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "metrics/calibration.h"

namespace proctex::metrics {

std::vector<float> ColourMetric::compute(const Analysis& analysis) const {
  const std::vector<float>* ch[3] = {&analysis.L, &analysis.a, &analysis.b};
  const std::size_t n = analysis.L.size();
  double mean[3] = {0, 0, 0};
  for (int c = 0; c < 3; ++c) {
    for (float v : *ch[c]) mean[c] += v;
    mean[c] /= static_cast<double>(n);
  }
  double cov[6] = {0, 0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const double d0 = (*ch[0])[i] - mean[0], d1 = (*ch[1])[i] - mean[1], d2 = (*ch[2])[i] - mean[2];
    cov[0] += d0 * d0;
    cov[1] += d0 * d1;
    cov[2] += d0 * d2;
    cov[3] += d1 * d1;
    cov[4] += d1 * d2;
    cov[5] += d2 * d2;
  }
  std::vector<float> f;
  f.reserve(feature_size());
  for (double m : mean) f.push_back(static_cast<float>(m));
  for (double c : cov) f.push_back(static_cast<float>(c / static_cast<double>(n)));
  // Quantiles from a fine histogram (0.05 units per bin, linear within a bin): O(n), where
  // nth_element per quantile cost more than everything else in the metric.
  constexpr float kLo[3] = {-5.0f, -160.0f, -160.0f}, kHi[3] = {105.0f, 160.0f, 160.0f};
  constexpr float kBinWidth = 0.05f;
  std::vector<uint32_t> hist;
  for (int c = 0; c < 3; ++c) {
    const int bins = static_cast<int>((kHi[c] - kLo[c]) / kBinWidth);
    hist.assign(bins, 0);
    for (float v : *ch[c]) {
      int k = static_cast<int>((v - kLo[c]) / kBinWidth);
      hist[std::clamp(k, 0, bins - 1)]++;
    }
    int q = 1;
    uint64_t below = 0;
    for (int k = 0; k < bins && q <= kQuantiles; ++k) {
      while (q <= kQuantiles) {
        const double target = static_cast<double>(q) / (kQuantiles + 1) * static_cast<double>(n);
        if (below + hist[k] < target || hist[k] == 0) break;
        const double frac = (target - static_cast<double>(below)) / hist[k];
        f.push_back(kLo[c] + (k + static_cast<float>(frac)) * kBinWidth);
        ++q;
      }
      below += hist[k];
    }
    while (q++ <= kQuantiles) f.push_back(kHi[c]);
  }
  return f;
}

namespace {
Eigen::Matrix3d covariance(std::span<const float> f) {
  Eigen::Matrix3d m;
  m << f[3], f[4], f[5], f[4], f[6], f[7], f[5], f[7], f[8];
  return m;
}

Eigen::Matrix3d psd_sqrt(const Eigen::Matrix3d& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(m);
  Eigen::Vector3d ev = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
}
}  // namespace

double ColourMetric::distance(std::span<const float> a, std::span<const float> b) const {
  double dm2 = 0;
  for (int c = 0; c < 3; ++c) dm2 += (static_cast<double>(a[c]) - b[c]) * (a[c] - b[c]);
  const Eigen::Matrix3d ca = covariance(a), cb = covariance(b);
  const Eigen::Matrix3d sb = psd_sqrt(cb);
  const Eigen::Matrix3d cross = psd_sqrt(sb * ca * sb);
  const double tr = std::max(0.0, ca.trace() + cb.trace() - 2.0 * cross.trace());
  const double w2 = std::sqrt(dm2 + tr);
  double q2 = 0;
  for (int i = 9; i < 9 + 3 * kQuantiles; ++i) q2 += (static_cast<double>(a[i]) - b[i]) * (a[i] - b[i]);
  const double q = std::sqrt(q2 / kQuantiles);
  return 0.5 * w2 + 0.5 * q;
}

double ColourMetric::scale() const { return calibration::kColourScale; }

}  // namespace proctex::metrics
