#pragma once
// The default metric: a weighted geometric combination of component metrics,
//   S = prod_k S_k^{w_k},  sum_k w_k = 1   (equivalently distance = sum_k w_k d_k / scale_k),
// so S stays in (0, 1], is 1 only when every component is 1, and one bad component pulls it
// down (an arithmetic mean would let a perfect colour match hide a wrong structure).
// Features are the components' features concatenated in order; the analysis (crop, resize,
// CIELAB) is done once for all of them. breakdown() reads every component's similarity from the
// composite features, which is what a match result reports as evidence.
// Version = 100 * own layout version + sum of the components' versions, so bumping any component
// makes cached composite features stale too.
#include <utility>

#include "metrics/metric.h"

namespace proctex::metrics {

class CompositeMetric final : public Metric {
 public:
  struct Component {
    std::shared_ptr<const Metric> metric;
    double weight = 0;
  };

  // Weights are normalised to sum 1; throws proctex::Error for no component, a negative weight or
  // all weights zero. A zero-weight component is computed (breakdown) but not ranked by.
  explicit CompositeMetric(std::vector<Component> components, std::string id = "composite");
  // spectrum, pyramid, colour, structure with the weights of metrics/calibration.h.
  static std::vector<Component> default_components();

  std::string id() const override { return id_; }
  int version() const override;
  std::string summary() const override;
  std::size_t feature_size() const override { return size_; }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override { return 1.0; }

  const std::vector<Component>& components() const { return components_; }
  // (component id, similarity) for each component, from composite feature vectors.
  std::vector<std::pair<std::string, double>> breakdown(std::span<const float> a,
                                                        std::span<const float> b) const;
  // A component's slice of a composite feature vector.
  std::span<const float> slice(std::span<const float> composite, std::size_t component) const;

 private:
  std::vector<Component> components_;
  std::vector<std::size_t> offsets_;
  std::size_t size_ = 0;
  std::string id_;
};

}  // namespace proctex::metrics
