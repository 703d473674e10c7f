#include "metrics/aligned.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Dense>

#include "core/error.h"
#include "metrics/fft.h"

namespace proctex::metrics {

std::vector<float> AlignedMetric::compute(const Analysis& analysis) const {
  const int n = analysis.size;
  if (n % size_ != 0)
    throw Error("the aligned metric needs an analysis resolution that is a multiple of " + std::to_string(size_),
                "use a multiple of the metric's size");
  const int f = n / size_;
  const size_t pixels = size_t(size_) * size_;
  const size_t half = size_t(size_) * (size_ / 2 + 1);
  // Linear RGB area-averaged to size x size, zero mean per channel.
  Eigen::MatrixXd rgb(pixels, 3);
  for (int y = 0; y < size_; ++y)
    for (int x = 0; x < size_; ++x)
      for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int dy = 0; dy < f; ++dy)
          for (int dx = 0; dx < f; ++dx) sum += analysis.rgb.pixel(x * f + dx, y * f + dy)[c];
        rgb(size_t(y) * size_ + x, c) = sum / (f * f);
      }
  rgb.rowwise() -= rgb.colwise().mean();
  // The planes compared are the image's principal colour components, strongest first: a shader
  // that mixes two colours by a mask has all its structure in the first one, whatever the colours
  // (in RGB channels a colour pair equal in one channel would leave that channel flat).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(rgb.transpose() * rgb);
  std::vector<float> out;
  out.reserve(feature_size());
  detail::FftwArray<float> plane(pixels);
  detail::FftwArray<detail::Complex> spectrum(half);
  for (int k = 2; k >= 0; --k) {  // eigenvalues ascend
    const Eigen::Vector3d axis = pca.eigenvectors().col(k);
    double norm = 0;
    for (size_t i = 0; i < pixels; ++i) {
      const double v = rgb.row(i).dot(axis);
      plane[i] = static_cast<float>(v);
      norm += v * v;
    }
    out.push_back(static_cast<float>(norm));
    detail::fft_r2c(size_, size_, plane, spectrum);
    for (size_t i = 0; i < half; ++i) {
      out.push_back(spectrum[i].real());
      out.push_back(spectrum[i].imag());
    }
  }
  return out;
}

std::vector<double> AlignedMetric::residuals(std::span<const float> a, std::span<const float> b) const {
  const size_t pixels = size_t(size_) * size_;
  const size_t half = size_t(size_) * (size_ / 2 + 1);
  const size_t stride = 1 + 2 * half;
  // residual[s]: sum over components of the fitted residual at circular shift s.
  std::vector<double> residual(pixels, 0.0);
  detail::FftwArray<detail::Complex> product(half);
  detail::FftwArray<float> correlation(pixels);
  for (int c = 0; c < 3; ++c) {
    const float* fa = a.data() + c * stride;
    const float* fb = b.data() + c * stride;
    const double na = fa[0], nb = fb[0];
    const double both = 0.5 * (na + nb);
    // A flat component (no structure to correlate) contributes its partner's energy, half of it.
    const bool flat = na <= 1e-12 * pixels || nb <= 1e-12 * pixels;
    if (flat) {
      for (auto& r : residual) r += both;
      continue;
    }
    for (size_t i = 0; i < half; ++i) {
      const detail::Complex xa(fa[1 + 2 * i], fa[2 + 2 * i]), xb(fb[1 + 2 * i], fb[2 + 2 * i]);
      product[i] = xa * std::conj(xb);
    }
    // correlation[s] = pixels * sum_x a(x + s) b(x): the unnormalised inverse; divided back out.
    detail::fft_c2r(size_, size_, product, correlation);
    const double inv = 1.0 / (double(pixels) * std::sqrt(na * nb));
    for (size_t s = 0; s < pixels; ++s) {
      const double r = std::clamp(double(correlation[s]) * inv, -1.0, 1.0);
      residual[s] += both * (1.0 - r * r);
    }
  }
  return residual;
}

double AlignedMetric::distance(std::span<const float> a, std::span<const float> b) const {
  const auto residual = residuals(a, b);
  const size_t at = std::min_element(residual.begin(), residual.end()) - residual.begin();
  // Between whole-pixel shifts: a parabola through the minimum and its neighbours, per axis. A
  // pattern that starts a fraction of a pixel away (stripes at 30 degrees, or the complementary
  // duty in swapped colours) is then as close as it looks, and the distance varies smoothly with a
  // parameter that moves the pattern instead of stepping from one whole shift to the next.
  const size_t n = size_t(size_);
  const size_t x = at % n, y = at / n;
  const auto value = [&](size_t xx, size_t yy) { return residual[(yy % n) * n + (xx % n)]; };
  const auto dip = [](double before, double centre, double after) {
    const double curvature = before - 2 * centre + after;
    return curvature > 0 ? (before - after) * (before - after) / (8 * curvature) : 0.0;
  };
  const double centre = residual[at];
  const double best = centre - dip(value(x + n - 1, y), centre, value(x + 1, y)) -
                      dip(value(x, y + n - 1), centre, value(x, y + 1));
  return std::sqrt(std::max(0.0, best) / (3.0 * double(residual.size())));
}

std::pair<int, int> AlignedMetric::best_shift(std::span<const float> a, std::span<const float> b) const {
  const auto residual = residuals(a, b);
  const size_t s = std::min_element(residual.begin(), residual.end()) - residual.begin();
  return {int(s % size_t(size_)), int(s / size_t(size_))};
}

}  // namespace proctex::metrics
