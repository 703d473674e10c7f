#pragma once
// Oriented multi-scale structure similarity, in the spirit of Portilla and Simoncelli (2000):
// the spectrum misses how energy is arranged (a brick wall and noise with the same spectrum
// differ in where and how the energy clusters); joint statistics of oriented band-pass
// responses capture edges, lines, periodic layouts and weaves.
//
// Filter bank: kScales scales (a Gaussian pyramid of lightness, 5-tap binomial, so every scale is
// filtered at its own resolution) x kOrientations orientations (0, 45, 90, 135 deg). Each filter is
// a complex (analytic, one half-plane) log-Gabor applied through FFTW: radial
// exp(-ln(f / 0.25)^2 / (2 * 0.45^2)) around 0.25 cycles/pixel, angular cos^2 of the angle to the
// filter's orientation. The magnitude |z| of a response is the local energy, its real part the
// band-pass signal.
// Features (191 floats), in groups:
//   energy      16  ln mean |z|^2 per band (contrast and spectral shape)
//   sparseness  16  std(|z|) / mean(|z|) per band (0.52 for Gaussian noise; higher for sparse edges)
//   kurtosis    16  ln kurtosis of Re z per band (ln 3 for Gaussian)
//   orient-corr 24  correlation of |z| between every pair of orientations at a scale
//   scale-corr  12  correlation of |z| with the same orientation one scale coarser
//   lowpass-ac  40  normalised autocorrelation of the Gaussian pyramid levels 0..4 at 8 offsets
//                   (1,0) (0,1) (1,1) (1,-1) (2,0) (0,2) (2,2) (2,-2)
//   energy-ac   64  normalised autocorrelation of |z| (mean removed) at (4,0) (0,4) (4,4) (4,-4):
//                   the layout of energy (periodicity of bricks and weaves)
//   pixel        3  ln variance, skewness, ln kurtosis of lightness
// Distance: per group, the mean squared difference divided by the group's unit (energy 1 nat,
// sparseness 0.1, kurtosis 0.5, correlations 0.2, autocorrelations 0.1, pixel 0.5), then the
// square root of the weighted mean over groups. Group weights (fitted by the retrieval
// evaluation, docs/metrics.md): energy 4, sparseness 0.5, pixel 2, the others 0 (computed and
// cached, but on the evaluation set they varied as much between seeds as between textures).
#include <span>

#include "metrics/metric.h"

namespace proctex::metrics {

class StructureMetric final : public Metric {
 public:
  static constexpr int kScales = 4;
  static constexpr int kOrientations = 4;

  std::string id() const override { return "structure"; }
  int version() const override { return 2; }
  std::string summary() const override {
    return "oriented multi-scale filter statistics (Portilla-Simoncelli-like)";
  }
  std::size_t feature_size() const override;

  // The feature groups in layout order, with the unit each group's differences are divided by
  // and its weight in the distance (exposed for the retrieval evaluation).
  struct Group {
    const char* name;
    int size;
    double unit;
    double weight;
  };
  static std::span<const Group> groups();
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override;
  // Feature groups for the default metric (composite.h): the unit-scaled RMS difference of each feature group.
  std::size_t group_count() const override;
  std::string group_name(std::size_t group) const override;
  void group_distances(std::span<const float> a, std::span<const float> b, double* out) const override;
};

}  // namespace proctex::metrics
