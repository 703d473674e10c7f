#include "metrics/colour.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "metrics/calibration.h"
#include "metrics/detail.h"

namespace proctex::metrics {

std::vector<float> ColourMetric::compute(const Analysis& analysis) const {
  const std::vector<float>* ch[3] = {&analysis.L, &analysis.a, &analysis.b};
  const std::size_t n = analysis.L.size();
  // Vectorised: float partial sums over row-sized chunks, accumulated in double.
  constexpr std::size_t kChunk = 256;
  double mean[3] = {0, 0, 0};
  for (int c = 0; c < 3; ++c) mean[c] = detail::sum(*ch[c]) / static_cast<double>(n);
  double cov[6] = {0, 0, 0, 0, 0, 0};
  const float m0 = static_cast<float>(mean[0]), m1 = static_cast<float>(mean[1]), m2 = static_cast<float>(mean[2]);
  const float* p0 = analysis.L.data();
  const float* p1 = analysis.a.data();
  const float* p2 = analysis.b.data();
  for (std::size_t i0 = 0; i0 < n; i0 += kChunk) {
    const std::size_t i1 = std::min(n, i0 + kChunk);
    float s00 = 0, s01 = 0, s02 = 0, s11 = 0, s12 = 0, s22 = 0;
#pragma omp simd reduction(+ : s00, s01, s02, s11, s12, s22)
    for (std::size_t i = i0; i < i1; ++i) {
      const float d0 = p0[i] - m0, d1 = p1[i] - m1, d2 = p2[i] - m2;
      s00 += d0 * d0;
      s01 += d0 * d1;
      s02 += d0 * d2;
      s11 += d1 * d1;
      s12 += d1 * d2;
      s22 += d2 * d2;
    }
    cov[0] += s00;
    cov[1] += s01;
    cov[2] += s02;
    cov[3] += s11;
    cov[4] += s12;
    cov[5] += s22;
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
  std::vector<int> index(n);
  for (int c = 0; c < 3; ++c) {
    const int bins = static_cast<int>((kHi[c] - kLo[c]) / kBinWidth);
    hist.assign(bins, 0);
    // Bin indices in a vectorised pass, then the counting.
    const float* v = ch[c]->data();
    const float lo = kLo[c], inv_width = 1.0f / kBinWidth, top = static_cast<float>(bins - 1);
#pragma omp simd
    for (std::size_t i = 0; i < n; ++i)
      index[i] = static_cast<int>(std::clamp((v[i] - lo) * inv_width, 0.0f, top));
    for (std::size_t i = 0; i < n; ++i) hist[index[i]]++;
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


// Squared Bures distance of two covariances: the covariance part of the Gaussian 2-Wasserstein
// distance, tr(Ca) + tr(Cb) - 2 tr((Cb^1/2 Ca Cb^1/2)^1/2).
double bures2(std::span<const float> a, std::span<const float> b) {
  const Eigen::Matrix3d ca = covariance(a), cb = covariance(b);
  const Eigen::Matrix3d sb = psd_sqrt(cb);
  const Eigen::Matrix3d cross = psd_sqrt(sb * ca * sb);
  return std::max(0.0, ca.trace() + cb.trace() - 2.0 * cross.trace());
}
}  // namespace

double ColourMetric::distance(std::span<const float> a, std::span<const float> b) const {
  double dm2 = 0;
  for (int c = 0; c < 3; ++c) dm2 += (static_cast<double>(a[c]) - b[c]) * (a[c] - b[c]);
  const double w2 = std::sqrt(dm2 + bures2(a, b));
  double q2 = 0;
  for (int i = 9; i < 9 + 3 * kQuantiles; ++i) q2 += (static_cast<double>(a[i]) - b[i]) * (a[i] - b[i]);
  const double q = std::sqrt(q2 / kQuantiles);
  return 0.5 * w2 + 0.5 * q;
}

std::size_t ColourMetric::group_count() const { return 5; }

std::string ColourMetric::group_name(std::size_t group) const {
  static const char* names[5] = {"colour.mean-L", "colour.mean-ab", "colour.covariance",
                                 "colour.quantiles-L", "colour.quantiles-ab"};
  return names[group];
}

void ColourMetric::group_distances(std::span<const float> a, std::span<const float> b, double* out) const {
  out[0] = std::abs(static_cast<double>(a[0]) - b[0]);
  out[1] = std::hypot(static_cast<double>(a[1]) - b[1], static_cast<double>(a[2]) - b[2]);
  out[2] = std::sqrt(bures2(a, b));
  auto rms = [&](int from, int n) {
    double s = 0;
    for (int i = from; i < from + n; ++i) s += (static_cast<double>(a[i]) - b[i]) * (a[i] - b[i]);
    return std::sqrt(s / n);
  };
  out[3] = rms(9, kQuantiles);
  out[4] = rms(9 + kQuantiles, 2 * kQuantiles);
}

double ColourMetric::scale() const { return calibration::kColourScale; }

}  // namespace proctex::metrics
