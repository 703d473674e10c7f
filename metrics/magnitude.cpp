#include "metrics/magnitude.h"

#include <cmath>

#include "core/error.h"
#include "metrics/fft.h"

namespace proctex::metrics {

std::vector<float> MagnitudeMetric::compute(const Analysis& analysis) const {
  const int n = analysis.size;
  if (n % kSize != 0)
    throw Error("the magnitude metric needs an analysis resolution that is a multiple of " + std::to_string(kSize),
                "use 64, 128, 256, ...");
  const int f = n / kSize;
  const int half = kSize / 2 + 1;
  std::vector<float> out;
  out.reserve(feature_size());
  detail::FftwArray<float> in(size_t(kSize) * kSize);
  detail::FftwArray<detail::Complex> spectrum(size_t(kSize) * half);
  for (const auto* plane : {&analysis.L, &analysis.a, &analysis.b}) {
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        double sum = 0;
        for (int dy = 0; dy < f; ++dy)
          for (int dx = 0; dx < f; ++dx) sum += (*plane)[size_t(y * f + dy) * n + x * f + dx];
        in[size_t(y) * kSize + x] = static_cast<float>(sum / (f * f) / 100.0);
      }
    detail::fft_r2c(kSize, kSize, in, spectrum);
    for (size_t i = 0; i < size_t(kSize) * half; ++i)
      out.push_back(std::sqrt(std::abs(spectrum[i]) / float(kSize * kSize)));
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
