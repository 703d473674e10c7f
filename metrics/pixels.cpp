#include "metrics/pixels.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"

namespace proctex::metrics {

std::vector<float> PixelMetric::compute(const Analysis& analysis) const {
  const Image rgb = resize(analysis.rgb, size_, size_);
  const size_t plane = size_t(size_) * size_;
  std::vector<float> out(3 * plane);
  for (size_t i = 0; i < plane; ++i)
    for (int c = 0; c < 3; ++c) out[c * plane + i] = rgb.pixels[3 * i + c];
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

std::vector<float> moved_target(const Image& target, int dx, int dy, std::vector<uint8_t>& mask) {
  const int n = target.width;
  std::vector<float> wanted(3 * size_t(n) * n, 0.0f);
  mask.assign(size_t(n) * n, 0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int rx = x + dx, ry = y + dy;  // the render's pixel that matches target(x, y)
      if (rx < 0 || ry < 0 || rx >= n || ry >= n) continue;
      std::copy_n(target.pixel(x, y), 3, &wanted[3 * (size_t(ry) * n + rx)]);
      mask[size_t(ry) * n + rx] = 1;
    }
  return wanted;
}

Features PixelMetric::target_features(const Image& target, int dx, int dy) const {
  if (target.width != size_ || target.height != size_)
    throw Error("the pixel metric's target must be " + std::to_string(size_) + " px square",
                "resize the target to the metric's size first");
  std::vector<uint8_t> mask;
  const auto moved = moved_target(target, dx, dy, mask);
  const size_t plane = size_t(size_) * size_;
  Features f{id(), version(), size_, std::vector<float>(3 * plane, std::numeric_limits<float>::quiet_NaN())};
  for (size_t i = 0; i < plane; ++i)
    if (mask[i])
      for (int c = 0; c < 3; ++c) f.values[c * plane + i] = moved[3 * i + c];
  return f;
}

}  // namespace proctex::metrics
