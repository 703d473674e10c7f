#pragma once
// Colour-distribution similarity in CIELAB (the thesis's measures ignore colour; a photo has it).
//
// Features (36 floats): mean L*, a*, b* (3); covariance (6: LL, La, Lb, aa, ab, bb); nine
// quantiles (10%..90%) of each channel (27).
// Distance, in Delta E units: 0.5 * W2 + 0.5 * Q, where W2 is the 2-Wasserstein distance between
// the two Gaussians (mean + covariance: catches a colour shift and a change of contrast or
// saturation, including correlations between channels), and Q = sqrt(sum over channels and
// quantiles of the squared difference / 9), the 1-D Wasserstein distance of each channel's
// marginal (catches non-Gaussian shapes: a bimodal mortar-and-brick histogram).
#include "metrics/metric.h"

namespace proctex::metrics {

class ColourMetric final : public Metric {
 public:
  static constexpr int kQuantiles = 9;

  std::string id() const override { return "colour"; }
  int version() const override { return 2; }  // 2: vectorised sums (last bits)
  std::string summary() const override {
    return "CIELAB colour distribution: mean, covariance (Gaussian W2) and channel quantiles";
  }
  std::size_t feature_size() const override { return 3 + 6 + 3 * kQuantiles; }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override;
  // Feature groups for the default metric (composite.h): |difference of mean L*|, distance of mean (a*, b*), the covariance (Bures) part of the 2-Wasserstein distance, RMS difference of the L* quantiles, of the a* and b* quantiles.
  std::size_t group_count() const override;
  std::string group_name(std::size_t group) const override;
  void group_distances(std::span<const float> a, std::span<const float> b, double* out) const override;
};

}  // namespace proctex::metrics
