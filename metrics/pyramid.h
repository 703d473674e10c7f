#pragma once
// Laplacian-pyramid histogram similarity (Bourque thesis eq 4.11,
// S_L = sum_i w_i |h(L_i(T1)) - h(L_i(T2))|, after Heeger and Bergen).
//
// Features: lightness (L*/100); kLevels band-pass levels of a filter-subtract-decimate Laplacian
// pyramid (L_i = G_i - blur(G_i), G_{i+1} = decimate(blur(G_i)), 5-tap binomial, mirrored
// borders) - the same band split as Burt-Adelson without the upsampling step. Each level's values
// v are mapped to t = sign(v) sqrt(min(|v| / kRange, 1)) (band values are heavy-tailed: the
// square root gives the many small values resolution and keeps large edges on the axis) and
// histogrammed into kBins bins over [-1, 1] with linear (soft) binning, normalised to sum 1.
// Absolute values, not normalised per image: contrast is part of a texture.
// Distance: sum_i w_i EMD_i / sum_i w_i, where EMD_i = sum |CDF_a - CDF_b| * bin width is the
// 1-D earth mover's distance. The thesis writes the bin-wise L1 difference; we take the L1
// difference of the cumulative histograms instead, because bin-wise L1 saturates as soon as two
// histograms stop overlapping (a slightly and a strongly blurred image would be equally far from
// the original) while the EMD keeps growing - needed for monotonic similarity.
// Weights w = (0.5, 1, 1, 1, 1), finest level first: the finest band is where JPEG artefacts,
// sensor noise and resampling live.
#include "metrics/metric.h"

namespace proctex::metrics {

class PyramidMetric final : public Metric {
 public:
  static constexpr int kLevels = 5;
  static constexpr int kBins = 32;
  static constexpr float kRange = 0.25f;  // lightness units mapped to t = +-1

  std::string id() const override { return "pyramid"; }
  int version() const override { return 1; }
  std::string summary() const override {
    return "histograms of Laplacian-pyramid levels of lightness (thesis eq 4.11)";
  }
  std::size_t feature_size() const override { return kLevels * kBins; }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override;
  // Feature groups for the default metric (composite.h): the EMD of each level.
  std::size_t group_count() const override;
  std::string group_name(std::size_t group) const override;
  void group_distances(std::span<const float> a, std::span<const float> b, double* out) const override;
};

}  // namespace proctex::metrics
