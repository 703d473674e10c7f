#pragma once
// Pixel-for-pixel difference in the image's own colours, at one fixed registration: the last step
// of recovering a deterministic pattern's exact parameters (search/: after the counts and the
// shape are found by the statistics, the magnitude and the registered-pixel metric, aligned.h).
//
// The statistical metrics are blind to what is left once a pattern is nearly right: a softness
// traded against a duty and a colour renders within RGB RMS 0.005 of the target (docs/
// match-evaluation.md), and only the pixels tell them apart. This metric compares exactly that:
// linear RGB, no colour fit, no translation search. The translation is fixed when the target's
// features are made (target_features): the target is moved so that it lines up with renders
// made at the shader's own origin, and the pixels it does not cover are left out (NaN).
// Distance: the mean squared RGB difference over the pixels both images define (squared, so that
// log similarity is quadratic near the optimum, where BOBYQA's models are exact). Symmetric; 0 for
// equal images. Not registered as a named metric: it is not a texture similarity.
#include <cstdint>
#include <vector>

#include "image/image.h"
#include "metrics/metric.h"

namespace proctex::metrics {

class PixelMetric final : public Metric {
 public:
  explicit PixelMetric(int size = kDefaultResolution) : size_(size) {}
  int size() const { return size_; }

  std::string id() const override { return "pixels"; }
  int version() const override { return 1; }
  std::string summary() const override { return "RGB RMS difference at a fixed registration (exact patterns)"; }
  std::size_t feature_size() const override { return 3 * std::size_t(size_) * size_; }
  // Linear RGB planes, the analysis resized area-correctly to size x size.
  std::vector<float> compute(const Analysis& analysis) const override;
  // Mean squared RGB difference over the entries finite in both (1 when none is: nothing in
  // common). rms() is its square root.
  double distance(std::span<const float> a, std::span<const float> b) const override;
  // RMS 0.01 maps to similarity 1/e: a pixel-exact result (RMS <= 0.005) scores above 0.77.
  double scale() const override { return 1e-4; }
  // The RGB RMS difference of a similarity this metric gave.
  double rms(double similarity) const;

  // Features of `target` (size x size, linear RGB) as a render at the shader's origin sees it:
  // render(x + dx, y + dy) ~ target(x, y) (AlignedMetric::register_rgb's convention), pixels of
  // the render that the moved target does not cover are NaN.
  Features target_features(const Image& target, int dx, int dy) const;

 private:
  int size_;
};

// `target` (square) moved the same way, as interleaved RGB the side of the target: the render's
// pixel (x + dx, y + dy) gets target(x, y); `mask` (one byte per pixel) marks the pixels the moved
// target covers, the others are 0.
std::vector<float> moved_target(const Image& target, int dx, int dy, std::vector<uint8_t>& mask);

}  // namespace proctex::metrics
