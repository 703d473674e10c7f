#include "metrics/magnitude.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "metrics/fft.h"

namespace proctex::metrics {

namespace {

// Blurs one plane's r2c magnitudes (size x (size/2+1)) with a Gaussian of `sigma` bins. The
// spectrum is periodic in both axes and symmetric (|F(-k)| = |F(k)|), so the blur runs on the
// whole size x size plane rebuilt from the half, with wrap-around.
void blur_half_spectrum(float* half_plane, int size, double sigma) {
  const int half = size / 2 + 1;
  std::vector<float> full(size_t(size) * size), tmp(full.size());
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      full[size_t(y) * size + x] = x < half ? half_plane[size_t(y) * half + x]
                                            : half_plane[size_t((size - y) % size) * half + (size - x)];
  const int radius = std::max(1, int(std::ceil(3 * sigma)));
  std::vector<float> w(2 * radius + 1);
  float total = 0;
  for (int k = -radius; k <= radius; ++k) total += w[k + radius] = float(std::exp(-0.5 * k * k / (sigma * sigma)));
  for (auto& v : w) v /= total;
  // Rows: each padded with its wrapped ends, so the taps need no modulo (the polish blurs three
  // planes per render, hundreds of renders per match).
  std::vector<float> padded(size_t(size) + 2 * radius);
  for (int y = 0; y < size; ++y) {
    const float* row = &full[size_t(y) * size];
    for (int i = 0; i < size + 2 * radius; ++i) padded[i] = row[((i - radius) % size + size) % size];
    float* out = &tmp[size_t(y) * size];
    for (int x = 0; x < size; ++x) {
      float sum = 0;
      for (int k = 0; k <= 2 * radius; ++k) sum += w[k] * padded[x + k];
      out[x] = sum;
    }
  }
  // Columns, a whole row of taps at a time: only the stored half of the spectrum is needed.
  for (int y = 0; y < size; ++y) {
    float* out = half_plane + size_t(y) * half;
    std::fill(out, out + half, 0.0f);
    for (int k = -radius; k <= radius; ++k) {
      const float* row = &tmp[size_t(((y + k) % size + size) % size) * size];
      const float wk = w[k + radius];
      for (int x = 0; x < half; ++x) out[x] += wk * row[x];
    }
  }
}

}  // namespace

std::vector<float> MagnitudeMetric::compute(const Analysis& analysis) const {
  const int n = analysis.size;
  if (n % size_ != 0)
    throw Error("the magnitude metric needs an analysis resolution that is a multiple of " + std::to_string(size_),
                "use a multiple of the metric's size");
  const int f = n / size_;
  const int half = size_ / 2 + 1;
  std::vector<float> out;
  out.reserve(feature_size());
  detail::FftwArray<float> in(size_t(size_) * size_);
  detail::FftwArray<detail::Complex> spectrum(size_t(size_) * half);
  for (const auto* plane : {&analysis.L, &analysis.a, &analysis.b}) {
    for (int y = 0; y < size_; ++y)
      for (int x = 0; x < size_; ++x) {
        double sum = 0;
        for (int dy = 0; dy < f; ++dy)
          for (int dx = 0; dx < f; ++dx) sum += (*plane)[size_t(y * f + dy) * n + x * f + dx];
        in[size_t(y) * size_ + x] = static_cast<float>(sum / (f * f) / 100.0);
      }
    detail::fft_r2c(size_, size_, in, spectrum);
    const size_t start = out.size();
    for (size_t i = 0; i < size_t(size_) * half; ++i)
      out.push_back(std::sqrt(std::abs(spectrum[i]) / float(size_ * size_)));
    if (blur_ > 0) blur_half_spectrum(out.data() + start, size_, blur_);
  }
  return out;
}

double MagnitudeMetric::distance(std::span<const float> a, std::span<const float> b) const {
  double sum = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const double d = double(a[i]) - double(b[i]);
    sum += d * d;
  }
  return std::sqrt(sum / double(a.size()));
}

}  // namespace proctex::metrics
