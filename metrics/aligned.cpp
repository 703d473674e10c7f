#include "metrics/aligned.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Dense>

#include "core/error.h"
#include "metrics/fft.h"

namespace proctex::metrics {

namespace {

// Summed-area table of a size x size plane, (size + 1)^2 with a zero first row and column.
std::vector<double> summed_area(const float* plane, int size, bool squared) {
  const size_t w = size_t(size) + 1;
  std::vector<double> t(w * w, 0.0);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const double v = plane[size_t(y) * size + x];
      t[(y + 1) * w + x + 1] = (squared ? v * v : v) + t[y * w + x + 1] + t[(y + 1) * w + x] - t[y * w + x];
    }
  return t;
}

// Sum over the rectangle [x0, x1) x [y0, y1) of a summed-area table of side `size`.
double rect_sum(const std::vector<double>& t, int size, int x0, int y0, int x1, int y1) {
  const size_t w = size_t(size) + 1;
  return t[y1 * w + x1] - t[y0 * w + x1] - t[y1 * w + x0] + t[y0 * w + x0];
}

// The best shift's index in a residual window: the smallest residual, and among near-equal ones
// (a pattern that is constant along one direction fits at every shift along it) the shortest shift.
size_t best_index(const std::vector<double>& residual, int reach) {
  const int window = 2 * reach + 1;
  const double least = *std::min_element(residual.begin(), residual.end());
  double mean = 0;
  for (double r : residual) mean += r;
  const double tie = least + 1e-6 * (mean / double(residual.size()) + 1e-30);
  size_t best = 0;
  int best_length = -1;
  for (size_t i = 0; i < residual.size(); ++i) {
    if (residual[i] > tie) continue;
    const int length = std::abs(int(i % window) - reach) + std::abs(int(i / window) - reach);
    if (best_length < 0 || length < best_length) {
      best = i;
      best_length = length;
    }
  }
  return best;
}

}  // namespace

std::vector<float> AlignedMetric::compute(const Analysis& analysis) const {
  const int n = analysis.size;
  if (n % size_ != 0)
    throw Error("the aligned metric needs an analysis resolution that is a multiple of " + std::to_string(size_),
                "use a multiple of the metric's size");
  const int f = n / size_;
  const size_t pixels = size_t(size_) * size_;
  const int padded = 2 * size_;
  const size_t half = size_t(padded) * (padded / 2 + 1);
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
  detail::FftwArray<float> plane(size_t(padded) * padded);
  detail::FftwArray<detail::Complex> spectrum(half);
  for (int k = 2; k >= 0; --k) {  // eigenvalues ascend
    const Eigen::Vector3d axis = pca.eigenvectors().col(k);
    std::fill(plane.data(), plane.data() + plane.size(), 0.0f);
    for (int y = 0; y < size_; ++y)
      for (int x = 0; x < size_; ++x) {
        const float v = static_cast<float>(rgb.row(size_t(y) * size_ + x).dot(axis));
        out.push_back(v);
        plane[size_t(y) * padded + x] = v;
      }
    // Zero-padded to twice the side: the circular correlation of the padded planes is the plain
    // (non-wrapping) correlation of the planes for every shift below the side.
    detail::fft_r2c(padded, padded, plane, spectrum);
    for (size_t i = 0; i < half; ++i) {
      out.push_back(spectrum[i].real());
      out.push_back(spectrum[i].imag());
    }
  }
  return out;
}

std::vector<double> AlignedMetric::residuals(std::span<const float> a, std::span<const float> b) const {
  const int n = size_, padded = 2 * size_, reach = max_shift();
  const size_t pixels = size_t(n) * n;
  const size_t half = size_t(padded) * (padded / 2 + 1);
  const size_t stride = pixels + 2 * half;
  const int window = 2 * reach + 1;
  // residual[(dy + reach) * window + dx + reach]: per-pixel energy left unexplained, summed over
  // the components, on the overlap of the two images at shift (dx, dy).
  std::vector<double> residual(size_t(window) * window, 0.0);
  detail::FftwArray<detail::Complex> product(half);
  detail::FftwArray<float> correlation(size_t(padded) * padded);
  for (int c = 0; c < 3; ++c) {
    const float* pa = a.data() + c * stride;
    const float* pb = b.data() + c * stride;
    const float* fa = pa + pixels;
    const float* fb = pb + pixels;
    for (size_t i = 0; i < half; ++i)
      product[i] = detail::Complex(fa[2 * i], fa[2 * i + 1]) * std::conj(detail::Complex(fb[2 * i], fb[2 * i + 1]));
    // correlation[s] = padded^2 * sum_p a(p + s) b(p): the unnormalised inverse.
    detail::fft_c2r(padded, padded, product, correlation);
    const auto sa = summed_area(pa, n, false), saa = summed_area(pa, n, true);
    const auto sb = summed_area(pb, n, false), sbb = summed_area(pb, n, true);
    const double scale = 1.0 / (double(padded) * padded);
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        // b's pixels p with p + (dx, dy) inside a: the overlap, in b's and in a's coordinates.
        const int bx0 = std::max(0, -dx), bx1 = std::min(n, n - dx), by0 = std::max(0, -dy), by1 = std::min(n, n - dy);
        const double count = double(bx1 - bx0) * (by1 - by0);
        const double sum_a = rect_sum(sa, n, bx0 + dx, by0 + dy, bx1 + dx, by1 + dy);
        const double sum_aa = rect_sum(saa, n, bx0 + dx, by0 + dy, bx1 + dx, by1 + dy);
        const double sum_b = rect_sum(sb, n, bx0, by0, bx1, by1);
        const double sum_bb = rect_sum(sbb, n, bx0, by0, bx1, by1);
        const double cross = correlation[size_t((dy + padded) % padded) * padded + (dx + padded) % padded] * scale;
        const double var_a = std::max(0.0, sum_aa - sum_a * sum_a / count);
        const double var_b = std::max(0.0, sum_bb - sum_b * sum_b / count);
        const double cov = cross - sum_a * sum_b / count;
        // A flat component (no structure to correlate) leaves its partner's energy unexplained.
        const double r2 = var_a > 1e-12 * count && var_b > 1e-12 * count
                              ? std::min(1.0, cov * cov / (var_a * var_b)) : 0.0;
        residual[size_t(dy + reach) * window + dx + reach] += 0.5 * (var_a + var_b) / count * (1.0 - r2);
      }
  }
  return residual;
}

double AlignedMetric::distance(std::span<const float> a, std::span<const float> b) const {
  const auto residual = residuals(a, b);
  const int window = 2 * max_shift() + 1;
  const size_t at = best_index(residual, max_shift());
  // Between whole-pixel shifts: a parabola through the minimum and its neighbours, per axis. A
  // pattern that starts a fraction of a pixel away (stripes at 30 degrees, or the complementary
  // duty in swapped colours) is then as close as it looks, and the distance varies smoothly with a
  // parameter that moves the pattern instead of stepping from one whole shift to the next.
  const int x = int(at % window), y = int(at / window);
  const auto dip = [](double before, double centre, double after) {
    const double curvature = before - 2 * centre + after;
    return curvature > 0 ? (before - after) * (before - after) / (8 * curvature) : 0.0;
  };
  const double centre = residual[at];
  double best = centre;
  if (x > 0 && x + 1 < window) best -= dip(residual[at - 1], centre, residual[at + 1]);
  if (y > 0 && y + 1 < window) best -= dip(residual[at - window], centre, residual[at + window]);
  return std::sqrt(std::max(0.0, best) / 3.0);
}

std::pair<int, int> AlignedMetric::best_shift(std::span<const float> a, std::span<const float> b) const {
  const auto residual = residuals(a, b);
  const int window = 2 * max_shift() + 1;
  const size_t s = best_index(residual, max_shift());
  return {int(s % window) - max_shift(), int(s / window) - max_shift()};
}

AlignedMetric::Registration AlignedMetric::register_rgb(const Image& target, const Image& render) {
  const int n = target.width;
  if (target.height != n || render.width != n || render.height != n || n < 4)
    throw Error("registering images needs two square images of one side", "resize both to the same size");
  // Every shift at once: the sum of squared differences on the overlap is sum a^2 + sum b^2 -
  // 2 sum ab, the squares from summed-area tables, the cross term from an FFT correlation of the
  // zero-padded channels (the plain, non-wrapping correlation for shifts below the side).
  const int padded = 2 * n, reach = n / 4, window = 2 * reach + 1;
  const size_t pixels = size_t(n) * n, half = size_t(padded) * (padded / 2 + 1);
  std::vector<double> ssd(size_t(window) * window, 0.0);
  detail::FftwArray<float> plane(size_t(padded) * padded), correlation(size_t(padded) * padded);
  detail::FftwArray<detail::Complex> fa(half), fb(half);
  std::vector<float> ca(pixels), cb(pixels);
  for (int c = 0; c < 3; ++c) {
    for (size_t i = 0; i < pixels; ++i) {
      ca[i] = render.pixels[3 * i + c];
      cb[i] = target.pixels[3 * i + c];
    }
    for (auto [values, spectrum] : {std::pair{&ca, &fa}, std::pair{&cb, &fb}}) {
      std::fill(plane.data(), plane.data() + plane.size(), 0.0f);
      for (int y = 0; y < n; ++y) std::copy_n(values->data() + size_t(y) * n, n, plane.data() + size_t(y) * padded);
      detail::fft_r2c(padded, padded, plane, *spectrum);
    }
    for (size_t i = 0; i < half; ++i) fa[i] *= std::conj(fb[i]);
    detail::fft_c2r(padded, padded, fa, correlation);  // padded^2 * sum_p a(p + s) b(p)
    const auto saa = summed_area(ca.data(), n, true), sbb = summed_area(cb.data(), n, true);
    const double scale = 1.0 / (double(padded) * padded);
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const int bx0 = std::max(0, -dx), bx1 = std::min(n, n - dx), by0 = std::max(0, -dy), by1 = std::min(n, n - dy);
        const double cross = correlation[size_t((dy + padded) % padded) * padded + (dx + padded) % padded] * scale;
        ssd[size_t(dy + reach) * window + dx + reach] += rect_sum(saa, n, bx0 + dx, by0 + dy, bx1 + dx, by1 + dy) +
                                                         rect_sum(sbb, n, bx0, by0, bx1, by1) - 2 * cross;
      }
  }
  std::vector<double> mse(ssd.size());
  for (int dy = -reach; dy <= reach; ++dy)
    for (int dx = -reach; dx <= reach; ++dx) {
      const size_t i = size_t(dy + reach) * window + dx + reach;
      mse[i] = std::max(0.0, ssd[i]) / (3.0 * (n - std::abs(dx)) * (n - std::abs(dy)));
    }
  const size_t at = best_index(mse, reach);
  const int dx = int(at % window) - reach, dy = int(at / window) - reach;
  // The reported residual directly at that shift: the FFT's a^2 + b^2 - 2ab cancels to ~1e-4.
  double sum = 0;
  for (int y = std::max(0, -dy); y < std::min(n, n - dy); ++y)
    for (int x = std::max(0, -dx); x < std::min(n, n - dx); ++x) {
      const float* p = target.pixel(x, y);
      const float* q = render.pixel(x + dx, y + dy);
      for (int c = 0; c < 3; ++c) sum += double(p[c] - q[c]) * (p[c] - q[c]);
    }
  return {std::sqrt(sum / (3.0 * (n - std::abs(dx)) * (n - std::abs(dy)))), dx, dy};
}

}  // namespace proctex::metrics
