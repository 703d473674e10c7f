#include "metrics/pixels.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace proctex::metrics {

std::vector<float> PixelMetric::compute(const Analysis& analysis) const {
  const int n = analysis.size;
  if (n % size_ != 0)
    throw Error("the pixel metric needs an analysis resolution that is a multiple of " + std::to_string(size_),
                "use a multiple of the metric's size");
  const int f = n / size_;
  const size_t plane = size_t(size_) * size_;
  std::vector<float> out(3 * plane);
  for (int y = 0; y < size_; ++y)
    for (int x = 0; x < size_; ++x)
      for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int dy = 0; dy < f; ++dy)
          for (int dx = 0; dx < f; ++dx) sum += analysis.rgb.pixel(x * f + dx, y * f + dy)[c];
        out[c * plane + size_t(y) * size_ + x] = static_cast<float>(sum / (f * f));
      }
  return out;
}

double PixelMetric::distance(std::span<const float> a, std::span<const float> b) const {
  double sum = 0;
  size_t count = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    if (!std::isfinite(a[i]) || !std::isfinite(b[i])) continue;
    const double d = double(a[i]) - double(b[i]);
    sum += d * d;
    ++count;
  }
  return count ? sum / double(count) : 1.0;
}

double PixelMetric::rms(double similarity) const {
  return std::sqrt(std::max(0.0, -std::log(similarity)) * scale());
}

Features PixelMetric::target_features(const Image& target, int dx, int dy) const {
  if (target.width != size_ || target.height != size_)
    throw Error("the pixel metric's target must be " + std::to_string(size_) + " px square",
                "resize the target to the metric's size first");
  const size_t plane = size_t(size_) * size_;
  Features f{id(), version(), size_, std::vector<float>(3 * plane, std::numeric_limits<float>::quiet_NaN())};
  for (int y = 0; y < size_; ++y)
    for (int x = 0; x < size_; ++x) {
      const int rx = x + dx, ry = y + dy;  // the render's pixel that matches target(x, y)
      if (rx < 0 || ry < 0 || rx >= size_ || ry >= size_) continue;
      for (int c = 0; c < 3; ++c) f.values[c * plane + size_t(ry) * size_ + rx] = target.pixel(x, y)[c];
    }
  return f;
}

}  // namespace proctex::metrics
