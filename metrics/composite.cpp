#include "metrics/composite.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <span>
#include <string>

#include "core/error.h"
#include "core/parallel.h"
#include "metrics/calibration.h"
#include "metrics/colour.h"
#include "metrics/pyramid.h"
#include "metrics/spectrum.h"
#include "metrics/structure.h"

namespace proctex::metrics {

namespace {
// 1: product of component similarities; 2: weighted sum of group distances (grouped form).
constexpr int kOwnVersionProduct = 1;
constexpr int kOwnVersionGrouped = 2;
// 3: "layout", the grouped form refitted with the shape-probe constraint.
constexpr int kOwnVersionLayout = 3;
}

CompositeMetric::CompositeMetric(std::vector<Component> components, std::string id)
    : components_(std::move(components)), id_(std::move(id)) {
  if (components_.empty()) throw Error("a composite metric needs at least one component");
  double total = 0;
  for (const Component& c : components_) {
    if (!c.metric || !(c.weight >= 0)) {
      throw Error("composite metric component without a metric or with a negative weight",
                  "give every component a metric and a weight >= 0");
    }
    total += c.weight;
  }
  if (!(total > 0)) throw Error("composite metric weights are all zero", "give a component a positive weight");
  for (Component& c : components_) {
    c.weight /= total;
    offsets_.push_back(size_);
    size_ += c.metric->feature_size();
    group_offsets_.push_back(group_names_.size());
    for (std::size_t g = 0; g < c.metric->group_count(); ++g) group_names_.push_back(c.metric->group_name(g));
  }
}

namespace {
std::vector<CompositeMetric::Component> with_group_shares(std::vector<CompositeMetric::Component> components,
                                                          const std::vector<double>& group_weights) {
  // Checks one weight >= 0 per group. Component weights are kept when given (reported; callers
  // that leave a component out keep the others' relative weights); all zero: each component's
  // share of the group weights.
  std::size_t at = 0;
  double total = 0, given = 0;
  std::vector<double> share;
  for (const auto& c : components) {
    if (!c.metric) throw Error("composite metric component without a metric");
    double sh = 0;
    for (std::size_t g = 0; g < c.metric->group_count(); ++g, ++at) {
      if (at >= group_weights.size() || !(group_weights[at] >= 0))
        throw Error("composite metric group weights: one weight >= 0 per feature group needed",
                    "give as many weights as the components have groups");
      sh += group_weights[at];
    }
    share.push_back(sh);
    total += sh;
    given += c.weight > 0 ? c.weight : 0.0;
  }
  if (at != group_weights.size())
    throw Error("composite metric group weights: one weight >= 0 per feature group needed",
                "give as many weights as the components have groups");
  if (!(total > 0)) throw Error("composite metric group weights are all zero", "give a group a positive weight");
  if (!(given > 0))
    for (std::size_t i = 0; i < components.size(); ++i) components[i].weight = share[i];
  return components;
}
}  // namespace

CompositeMetric::CompositeMetric(std::vector<Component> components, std::vector<double> group_weights,
                                 double scale, std::string id, double exponent, int own_version)
    : CompositeMetric(with_group_shares(std::move(components), group_weights), std::move(id)) {
  if (!(scale > 0)) throw Error("composite metric scale must be positive");
  if (!(exponent > 0 && exponent <= 1)) throw Error("composite metric exponent must be in (0, 1]");
  group_weights_ = std::move(group_weights);
  scale_ = scale;
  exponent_ = exponent;
  own_version_ = own_version;
}

std::vector<CompositeMetric::Component> CompositeMetric::default_components() {
  return {{std::make_shared<SpectrumMetric>(), 1.0},
          {std::make_shared<PyramidMetric>(), 1.0},
          {std::make_shared<ColourMetric>(), 1.0},
          {std::make_shared<StructureMetric>(), 1.0}};
}

std::shared_ptr<const CompositeMetric> CompositeMetric::make_default() {
  using namespace calibration;
  return std::make_shared<CompositeMetric>(
      std::vector<Component>{{std::make_shared<SpectrumMetric>(), kWeightSpectrum},
                             {std::make_shared<PyramidMetric>(), kWeightPyramid},
                             {std::make_shared<ColourMetric>(), kWeightColour},
                             {std::make_shared<StructureMetric>(), kWeightStructure}});
}

namespace {
// A grouped-form metric from a table of fitted group weights (metrics/calibration.h).
std::shared_ptr<const CompositeMetric> from_groups(std::span<const calibration::Group> groups, double scale,
                                                   double exponent, const std::string& id, int own_version) {
  std::vector<CompositeMetric::Component> components = CompositeMetric::default_components();
  // Component weights (reported, and used by callers that leave colour out to rank by structure):
  // each component's sum of fitted c_g, i.e. its share of the distance of a typical same-texture
  // pair (every group contributes about c_g there, d_g being near its median m_g).
  for (auto& c : components) {
    c.weight = 0;
    for (std::size_t g = 0; g < c.metric->group_count(); ++g)
      for (const calibration::Group& cg : groups)
        if (c.metric->group_name(g) == cg.name) c.weight += cg.weight;
  }
  std::vector<double> weights;
  for (const auto& c : components)
    for (std::size_t g = 0; g < c.metric->group_count(); ++g) {
      const std::string name = c.metric->group_name(g);
      double w = -1;
      for (const calibration::Group& cg : groups)
        if (name == cg.name) w = cg.weight / cg.median;
      if (w < 0)
        throw Error("metrics/calibration.h has no weight for feature group " + name,
                    "refit (bench_metrics_retrieval --fit-groups)");
      weights.push_back(w);
    }
  return std::make_shared<CompositeMetric>(std::move(components), std::move(weights), scale, id, exponent,
                                           own_version);
}
}  // namespace

std::shared_ptr<const CompositeMetric> CompositeMetric::make_layout() {
  return from_groups(calibration::kLayoutGroups, calibration::kLayoutScale, calibration::kLayoutExponent, "layout",
                     kOwnVersionLayout);
}

std::shared_ptr<const CompositeMetric> CompositeMetric::make_grouped() {
  return from_groups(calibration::kGroups, calibration::kCompositeScale, calibration::kCompositeExponent, "grouped",
                     kOwnVersionGrouped);
}

int CompositeMetric::version() const {
  int v = 100 * (group_weights_.empty() ? kOwnVersionProduct : own_version_);
  for (const Component& c : components_) v += c.metric->version();
  return v;
}

std::string CompositeMetric::summary() const {
  std::string s = group_weights_.empty() ? "weighted geometric mean of" : "weighted sum of feature-group distances; component shares";
  for (std::size_t i = 0; i < components_.size(); ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s %s %.2f", i ? "," : "", components_[i].metric->id().c_str(),
                  components_[i].weight);
    s += buf;
  }
  return s;
}

namespace {
constexpr int kComputeThreads = 2;
}  // namespace

std::vector<float> CompositeMetric::compute(const Analysis& analysis) const {
  // The components are independent, so two threads share them: a match computes features between
  // its renders (one refinement is a chain of render, features, render...), and the device's
  // threads wait meanwhile. Handed out last first: the costliest, structure, is last by default.
  // The values do not depend on the threads.
  std::vector<std::vector<float>> parts(components_.size());
  parallel_for(components_.size(), kComputeThreads, [&](size_t k) {
    const size_t i = components_.size() - 1 - k;
    parts[i] = components_[i].metric->compute(analysis);
  });
  std::vector<float> f;
  f.reserve(size_);
  for (const auto& part : parts) f.insert(f.end(), part.begin(), part.end());
  return f;
}

std::span<const float> CompositeMetric::slice(std::span<const float> composite,
                                              std::size_t component) const {
  return composite.subspan(offsets_.at(component), components_.at(component).metric->feature_size());
}

void CompositeMetric::group_distances(std::span<const float> a, std::span<const float> b, double* out) const {
  for (std::size_t i = 0; i < components_.size(); ++i)
    components_[i].metric->group_distances(slice(a, i), slice(b, i), out + group_offsets_[i]);
}

double CompositeMetric::distance(std::span<const float> a, std::span<const float> b) const {
  if (!group_weights_.empty()) {
    // Few groups (20 by default): a stack buffer, no allocation per similarity.
    double buf[64];
    std::vector<double> heap;
    double* g = buf;
    if (group_names_.size() > 64) {
      heap.resize(group_names_.size());
      g = heap.data();
    }
    group_distances(a, b, g);
    double d = 0;
    for (std::size_t k = 0; k < group_names_.size(); ++k)
      if (group_weights_[k] != 0) d += group_weights_[k] * g[k];
    return std::pow(d, exponent_);
  }
  double d = 0;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    const Metric& m = *components_[i].metric;
    if (components_[i].weight == 0) continue;  // computed for breakdown(), not ranked by
    d += components_[i].weight * m.distance(slice(a, i), slice(b, i)) / m.scale();
  }
  return d;
}

std::vector<std::pair<std::string, double>> CompositeMetric::breakdown(
    std::span<const float> a, std::span<const float> b) const {
  if (a.size() != size_ || b.size() != size_) {
    throw Error("composite feature vectors have the wrong length", "recompute the features");
  }
  std::vector<std::pair<std::string, double>> out;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    out.emplace_back(components_[i].metric->id(),
                     components_[i].metric->similarity(slice(a, i), slice(b, i)));
  }
  return out;
}

double CompositeMetric::similarity_without(std::span<const float> a, std::span<const float> b,
                                           std::string_view left_out) const {
  if (a.size() != size_ || b.size() != size_) {
    throw Error("composite feature vectors have the wrong length", "recompute the features");
  }
  bool known = false;
  double log_s = 0.0, weight = 0.0;
  for (std::size_t i = 0; i < components_.size(); ++i) {
    const Component& c = components_[i];
    if (c.metric->id() == left_out) {
      known = true;
      continue;
    }
    if (c.weight <= 0) continue;
    log_s += c.weight * std::log(std::max(c.metric->similarity(slice(a, i), slice(b, i)), 1e-300));
    weight += c.weight;
  }
  if (!known) throw Error("the composite metric has no component '" + std::string(left_out) + "'", "name one of its components");
  if (weight <= 0) throw Error("no weighted component is left without '" + std::string(left_out) + "'", "leave out another component");
  return std::exp(log_s / weight);
}

}  // namespace proctex::metrics
