#pragma once
// Registered-pixel similarity: how well one image reproduces another pixel for pixel, after the
// best integer translation and a per-channel gain and offset. For the last step of recovering a
// deterministic pattern's exact parameters (search/: after the counts are found).
//
// Once a pattern's counts and angles are right, what is still wrong is continuous: a duty, an edge
// softness, an amplitude. The statistical metrics see those weakly (a soft edge with a wider duty
// has nearly the statistics of a sharp one), the Fourier magnitude too; pixels see them directly.
// Two invariances keep it usable inside the search:
// - translation: the target need not start where the shader's origin is (cross-correlation by
//   FFT over shifts up to a quarter of the side, each normalised on the two images' overlap: a
//   pattern is rarely periodic on the image, so a wrap-around comparison would punish every shift;
//   the best shift is taken);
// - colour: each image is reduced to its principal colour components (linear RGB, strongest
//   first), and each component of one is fitted to the same-ranked one of the other by a gain and
//   an offset (the gain may be negative, so swapped colours are equal too). A shader that mixes two
//   colours by a mask is affine in the mask, so colours drop out and the search only moves the
//   shape; the colour fit (search/colour_fit.h) sets the colours afterwards.
// Distance: sqrt(min over shifts of sum_k (var x_k + var y_k) / 2 * (1 - r_k(shift)^2) / 3), with
// x_k, y_k the components on the overlap at that shift, r_k their correlation there; the minimum
// refined between whole-pixel shifts by a parabola per axis. Symmetric; 0 for the same image
// shifted by up to a quarter of its side (on the overlap) and in any two colours.
// Not a texture similarity: two seeds of a noise differ everywhere in it.
#include <utility>

#include "metrics/metric.h"

namespace proctex::metrics {

class AlignedMetric final : public Metric {
 public:
  static constexpr int kSize = 128;
  explicit AlignedMetric(int size = kSize) : size_(size) {}
  int size() const { return size_; }

  std::string id() const override { return "aligned"; }
  int version() const override { return 2; }
  std::string summary() const override {
    return "registered pixels: best translation and per-channel gain/offset, RMS residual (exact patterns)";
  }
  // Per principal component: its plane (size^2), then the r2c spectrum of the plane zero-padded
  // to twice the side (re, im pairs).
  std::size_t feature_size() const override {
    return 3 * (size_t(size_) * size_ + 2 * size_t(2 * size_) * (size_ + 1));
  }
  // Shifts tried in each direction: a quarter of the side (the overlap keeps >= 56% of the image).
  int max_shift() const { return size_ / 4; }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override { return 0.02; }

  // The shift (dx, dy), each within +-max_shift(), at which `a` matches `b` best:
  // a(x + dx, y + dy) ~ b(x, y) up to each component's gain and offset.
  std::pair<int, int> best_shift(std::span<const float> a, std::span<const float> b) const;

  // How exactly `render` reproduces `target` in its own colours (both square, same side): the RGB
  // RMS difference on their overlap at the best whole-pixel shift within a quarter of the side
  // (every shift, exactly, by FFT; ties to the shortest). No colour fit and no principal
  // components: a recovered pattern in the wrong colours is not exact, and stripes in swapped
  // colours are exact only at the shift that swaps them back.
  struct Registration {
    double rmse = 0.0;
    int dx = 0, dy = 0;  // render(x + dx, y + dy) ~ target(x, y), in the images' pixels
  };
  static Registration register_rgb(const Image& target, const Image& render);

 private:
  // The unexplained energy per pixel at every shift within +-max_shift(), row-major.
  std::vector<double> residuals(std::span<const float> a, std::span<const float> b) const;
  int size_;
};

}  // namespace proctex::metrics
