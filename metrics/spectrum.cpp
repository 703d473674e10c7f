#include "metrics/spectrum.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "metrics/calibration.h"
#include "metrics/detail.h"
#include "metrics/fft.h"

namespace proctex::metrics {
namespace {

constexpr float kPowerFloor = 1e-12f;

}  // namespace

std::vector<float> SpectrumMetric::averaged_power(const std::vector<float>& plane, int size) {
  const int c = size / 2;  // crop side
  const int hc = c / 2 + 1;
  std::vector<float> window(c);
  for (int i = 0; i < c; ++i)
    window[i] = 0.5f - 0.5f * std::cos(2.0f * std::numbers::pi_v<float> * (i + 0.5f) / c);
  double wsum = 0, w2sum = 0;
  for (int y = 0; y < c; ++y)
    for (int x = 0; x < c; ++x) {
      double w = window[x] * window[y];
      wsum += w;
      w2sum += w * w;
    }
  // Welch's method: a 3 x 3 grid of half-size crops overlapping by half (9 periodograms).
  const int offsets[9][2] = {{0, 0},         {c / 2, 0},     {c, 0},
                             {0, c / 2},     {c / 2, c / 2}, {c, c / 2},
                             {0, c},         {c / 2, c},     {c, c}};
  detail::FftwArray<float> in(static_cast<std::size_t>(c) * c);
  detail::FftwArray<detail::Complex> out(static_cast<std::size_t>(c) * hc);
  std::vector<float> power(static_cast<std::size_t>(c) * hc, 0.0f);
  for (const auto& o : offsets) {
    double m = 0;
    for (int y = 0; y < c; ++y)
      for (int x = 0; x < c; ++x)
        m += window[x] * window[y] * plane[static_cast<std::size_t>(o[1] + y) * size + o[0] + x];
    m /= wsum;
    for (int y = 0; y < c; ++y)
      for (int x = 0; x < c; ++x)
        in[static_cast<std::size_t>(y) * c + x] = static_cast<float>(
            (plane[static_cast<std::size_t>(o[1] + y) * size + o[0] + x] - m) * window[x] *
            window[y]);
    detail::fft_r2c(c, c, in, out);
    for (std::size_t i = 0; i < power.size(); ++i) power[i] += std::norm(out[i]);
  }
  const float norm = static_cast<float>(1.0 / (9.0 * w2sum));
  for (float& p : power) p *= norm;
  return power;
}

std::vector<float> SpectrumMetric::compute(const Analysis& analysis) const {
  const int c = analysis.size / 2;
  const int hc = c / 2 + 1;
  const std::vector<float> power = averaged_power(analysis.lightness, analysis.size);

  const double nyquist = c / 2.0;
  // Radial bins are uniform in u = ln(1 + r / 4) over r in [1, nyquist]: logarithmic at high
  // frequencies, wider at the lowest ones, where a bin would otherwise hold two or three
  // coefficients and its log power would be noise.
  auto warp = [](double r) { return std::log1p(r / 4.0); };
  const double u0 = warp(1.0), u1 = warp(nyquist);
  std::vector<double> radial(kRadialBins, 0.0);
  std::vector<int> radial_n(kRadialBins, 0);
  std::vector<double> orient(kOrientationBands * kOrientationBins, 0.0);
  std::vector<int> orient_n(kOrientationBands * kOrientationBins, 0);
  const double band_edges[kOrientationBands + 1] = {nyquist / 16, nyquist / 4, nyquist / 2,
                                                    nyquist * 1.0000001};
  for (int ky = 0; ky < c; ++ky) {
    const int fy = ky <= c / 2 ? ky : ky - c;
    for (int kx = 0; kx < hc; ++kx) {
      if (kx == 0 && fy < 0) continue;  // the other half of the kx = 0 column is redundant
      const double r = std::hypot(static_cast<double>(kx), static_cast<double>(fy));
      if (r < 1.0 || r > nyquist) continue;
      const double p = power[static_cast<std::size_t>(ky) * hc + kx];
      int rb = static_cast<int>((warp(r) - u0) / (u1 - u0) * kRadialBins);
      rb = std::clamp(rb, 0, kRadialBins - 1);
      radial[rb] += p;
      radial_n[rb]++;
      double theta = std::atan2(static_cast<double>(fy), static_cast<double>(kx));  // -pi/2..pi/2
      if (theta < 0) theta += std::numbers::pi;
      int ob = static_cast<int>(theta / std::numbers::pi * kOrientationBins + 0.5) % kOrientationBins;
      for (int band = 0; band < kOrientationBands; ++band) {
        if (r >= band_edges[band] && r < band_edges[band + 1]) {
          orient[band * kOrientationBins + ob] += p;
          orient_n[band * kOrientationBins + ob]++;
        }
      }
    }
  }
  std::vector<float> f;
  f.reserve(feature_size());
  float last = kPowerFloor;
  for (int i = 0; i < kRadialBins; ++i) {
    // A bin without samples (tiny resolutions) repeats its lower neighbour.
    float v = radial_n[i] ? static_cast<float>(radial[i] / radial_n[i]) : last;
    last = v;
    f.push_back(std::log10(std::max(v, kPowerFloor)));
  }
  for (int band = 0; band < kOrientationBands; ++band) {
    double total = 0;
    int n = 0;
    for (int o = 0; o < kOrientationBins; ++o) {
      total += orient[band * kOrientationBins + o];
      n += orient_n[band * kOrientationBins + o];
    }
    const double band_mean = n ? total / n : 0.0;
    for (int o = 0; o < kOrientationBins; ++o) {
      const int k = band * kOrientationBins + o;
      const double m = orient_n[k] ? orient[k] / orient_n[k] : band_mean;
      f.push_back(static_cast<float>(
          std::log10((m + kPowerFloor) / (band_mean + kPowerFloor))));
    }
  }
  return f;
}

double SpectrumMetric::distance(std::span<const float> a, std::span<const float> b) const {
  static const std::vector<double> weights = [] {
    std::vector<double> w;
    for (int i = 0; i < kRadialBins; ++i) w.push_back(1.0 - 0.75 * i / (kRadialBins - 1));
    for (int i = 0; i < kOrientationBins * kOrientationBands; ++i) w.push_back(0.5);
    return w;
  }();
  return detail::weighted_rms(a, b, weights);
}

std::size_t SpectrumMetric::group_count() const { return 2; }

std::string SpectrumMetric::group_name(std::size_t group) const {
  return group == 0 ? "spectrum.radial" : "spectrum.orientation";
}

void SpectrumMetric::group_distances(std::span<const float> a, std::span<const float> b, double* out) const {
  auto rms = [&](int from, int n) {
    double s = 0;
    for (int i = from; i < from + n; ++i) s += (static_cast<double>(a[i]) - b[i]) * (a[i] - b[i]);
    return std::sqrt(s / n);
  };
  out[0] = rms(0, kRadialBins);
  out[1] = rms(kRadialBins, kOrientationBins * kOrientationBands);
}

double SpectrumMetric::scale() const { return calibration::kSpectrumScale; }

}  // namespace proctex::metrics
