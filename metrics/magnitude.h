#pragma once
// Exact-pattern similarity: the full 2-D Fourier magnitude of each CIELAB plane, for telling the
// exact parameters of a deterministic pattern (a tiling, a shape, a checker) apart.
//
// The statistical metrics (spectrum bins, histograms, filter statistics) summarise a texture so
// that two renders with other seeds compare as equal; for a deterministic pattern that makes
// neighbouring parameter values (7 or 8 brick courses, a ratio of 2.6 or 2.7) almost equal too,
// and aliases (an English bond whose headers look like a running bond) score as well as the truth.
// The whole magnitude spectrum keeps every frequency and orientation of the pattern, so those
// differences are large, while the phase - where the pattern starts - is ignored: the target need
// not be aligned with the shader's origin. Not a texture similarity for stochastic textures (two
// seeds of noise differ everywhere in it): search/ uses it only to polish a deterministic match.
//
// Features: the analysis planes L*/100, a*/100, b*/100 area-averaged to size x size (default kSize;
// a size at which the pattern is above the Nyquist limit: 44 stripes alias at 64 px), FFTW r2c,
// sqrt(|F| / size^2) (compressive, stable near the many zero coefficients of a clean pattern; the
// DC term is the plane's mean, so the colour counts). Distance: RMS difference.
#include "metrics/metric.h"

namespace proctex::metrics {

class MagnitudeMetric final : public Metric {
 public:
  static constexpr int kSize = 64;
  // `blur`: Gaussian sigma in frequency bins applied to the magnitudes (0: none). A blurred
  // magnitude lets a search see a peak that is a few bins off (a stripe count or an angle not yet
  // right): the exact one is flat there. For coarse-to-fine searches only.
  explicit MagnitudeMetric(int size = kSize, double blur = 0.0) : size_(size), blur_(blur) {}
  int size() const { return size_; }

  std::string id() const override { return "magnitude"; }
  int version() const override { return 1; }
  std::string summary() const override {
    return "full 2-D Fourier magnitude of the CIELAB planes (exact patterns, phase ignored)";
  }
  std::size_t feature_size() const override { return 3 * size_t(size_) * (size_ / 2 + 1); }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override { return 0.02; }

 private:
  int size_;
  double blur_;
};

}  // namespace proctex::metrics
