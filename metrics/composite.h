#pragma once
// Combinations of component metrics. Two forms:
//  - grouped (registered as "grouped"): every component splits its distance into feature groups
//    (Metric::group_distances: spectrum radial/orientation, pyramid levels, colour mean/
//    covariance/quantiles, structure statistics); the distance is the square root of a weighted
//    sum over all groups,
//      d = sqrt(sum_g w_g d_g),   S = exp(-d / scale),
//    with w_g = c_g / m_g (m_g: the group's median distance between two renders of one texture,
//    c_g: the weight fitted by the retrieval evaluation) and scale set so that two renders of one
//    texture score 0.7 at the median (metrics/calibration.h, docs/metrics.md). The square root
//    (not fitted; ranking does not depend on it) puts unrelated textures at S ~0.1-0.25, where
//    the verdict thresholds of search/match.h expect them; the plain sum would give them ~0;
//  - product (the default metric "composite", and plug-in combinations): S = prod_k S_k^{w_k},
//    sum_k w_k = 1.
// Either way S stays in (0, 1], is 1 only when every group (component) distance is 0, and one bad
// part pulls it down (a perfect colour match cannot hide a wrong structure).
// Features are the components' features concatenated in order; the analysis (crop, resize,
// CIELAB) is done once for all of them. breakdown() reads every component's similarity from the
// composite features, which is what a match result reports as evidence.
// Version = 100 * own layout version + sum of the components' versions, so bumping any component
// makes cached composite features stale too.
#include <memory>
#include <string_view>
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
  // Grouped form: one weight >= 0 per feature group of the components, in order (components'
  // group_count() each), and the distance that maps to 1/e. Component weights are then only
  // reported (components(); used by callers that leave a component out, e.g. search ranking
  // starts by structure); all 0: each component's share of the group weights.
  // d = (sum_g w_g d_g)^exponent; own_version tells fits apart (it enters version()).
  CompositeMetric(std::vector<Component> components, std::vector<double> group_weights, double scale,
                  std::string id = "composite", double exponent = 0.5, int own_version = 2);
  // spectrum, pyramid, colour, structure, weight 1 each.
  static std::vector<Component> default_components();
  // The default metric "composite": product form, component weights of metrics/calibration.h.
  static std::shared_ptr<const CompositeMetric> make_default();
  // "layout": the grouped form refitted with the shape probes as a constraint (kLayoutGroups of
  // metrics/calibration.h); not the default: the matcher still misses the 4-pointed star with it.
  static std::shared_ptr<const CompositeMetric> make_layout();
  // "grouped": the grouped form with the group weights fitted by the retrieval evaluation
  // (metrics/calibration.h). Better retrieval than the default (docs/metrics.md) but not the
  // default yet: it matches a 4-pointed star as a circle (tests/search/match_test.cpp).
  static std::shared_ptr<const CompositeMetric> make_grouped();

  std::string id() const override { return id_; }
  int version() const override;
  std::string summary() const override;
  std::size_t feature_size() const override { return size_; }
  std::vector<float> compute(const Analysis& analysis) const override;
  double distance(std::span<const float> a, std::span<const float> b) const override;
  double scale() const override { return scale_; }
  // Grouped form: d = (sum_g w_g d_g)^exponent.
  double exponent() const { return exponent_; }
  std::size_t group_count() const override { return group_names_.size(); }
  std::string group_name(std::size_t group) const override { return group_names_.at(group); }
  void group_distances(std::span<const float> a, std::span<const float> b, double* out) const override;
  // Weight of each group (grouped form; empty for the product form).
  const std::vector<double>& group_weights() const { return group_weights_; }

  const std::vector<Component>& components() const { return components_; }
  // (component id, similarity) for each component, from composite feature vectors.
  std::vector<std::pair<std::string, double>> breakdown(std::span<const float> a,
                                                        std::span<const float> b) const;
  // The product-form similarity of the other components, their weights renormalised to sum 1:
  // what the composite says with one kind of evidence left out (the colour, for samples whose
  // colours are random; the spectrum, for clean patterns whose peaks it demands in the very bins).
  // Throws proctex::Error for an unknown component or when no weighted component is left.
  double similarity_without(std::span<const float> a, std::span<const float> b, std::string_view left_out) const;
  // A component's slice of a composite feature vector.
  std::span<const float> slice(std::span<const float> composite, std::size_t component) const;

 private:
  std::vector<Component> components_;
  std::vector<std::size_t> offsets_;
  std::size_t size_ = 0;
  std::string id_;
  std::vector<std::string> group_names_;
  std::vector<std::size_t> group_offsets_;  // first group of each component
  std::vector<double> group_weights_;
  double scale_ = 1.0;
  double exponent_ = 0.5;
  int own_version_ = 1;
};

}  // namespace proctex::metrics
