#include "metrics/composite.h"

#include <cstdio>

#include "core/error.h"
#include "metrics/calibration.h"
#include "metrics/colour.h"
#include "metrics/pyramid.h"
#include "metrics/spectrum.h"
#include "metrics/structure.h"

namespace proctex::metrics {

namespace {
constexpr int kOwnVersion = 1;
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
  }
}

std::vector<CompositeMetric::Component> CompositeMetric::default_components() {
  using namespace calibration;
  return {{std::make_shared<SpectrumMetric>(), kWeightSpectrum},
          {std::make_shared<PyramidMetric>(), kWeightPyramid},
          {std::make_shared<ColourMetric>(), kWeightColour},
          {std::make_shared<StructureMetric>(), kWeightStructure}};
}

int CompositeMetric::version() const {
  int v = 100 * kOwnVersion;
  for (const Component& c : components_) v += c.metric->version();
  return v;
}

std::string CompositeMetric::summary() const {
  std::string s = "weighted geometric mean of";
  for (std::size_t i = 0; i < components_.size(); ++i) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s %s %.2f", i ? "," : "", components_[i].metric->id().c_str(),
                  components_[i].weight);
    s += buf;
  }
  return s;
}

std::vector<float> CompositeMetric::compute(const Analysis& analysis) const {
  std::vector<float> f;
  f.reserve(size_);
  for (const Component& c : components_) {
    std::vector<float> part = c.metric->compute(analysis);
    f.insert(f.end(), part.begin(), part.end());
  }
  return f;
}

std::span<const float> CompositeMetric::slice(std::span<const float> composite,
                                              std::size_t component) const {
  return composite.subspan(offsets_.at(component), components_.at(component).metric->feature_size());
}

double CompositeMetric::distance(std::span<const float> a, std::span<const float> b) const {
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

}  // namespace proctex::metrics
