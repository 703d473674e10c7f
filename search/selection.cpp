#include "search/selection.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "metrics/composite.h"
#include "search/selection_model.h"

namespace proctex::search {

namespace model = selection_model;

std::vector<TargetView> target_views(const Image& photo, int resolution) {
  const Image square = center_crop_square(photo);
  std::vector<TargetView> views{{"whole", square}};
  const char* names[] = {"half", "quarter"};
  int side = square.width / 2;
  for (const char* name : names) {
    if (side < resolution) break;
    const int offset = (square.width - side) / 2;
    views.push_back({name, crop(square, offset, offset, side, side)});
    side /= 2;
  }
  return views;
}

double structural_similarity(const metrics::Metric& metric, const metrics::Features& a, std::span<const float> b) {
  const auto* composite = dynamic_cast<const metrics::CompositeMetric*>(&metric);
  if (!composite) return metric.similarity(a.values, b);
  const auto& components = composite->components();
  double log_s = 0.0, weight = 0.0;
  for (size_t k = 0; k < components.size(); ++k) {
    const auto& c = components[k];
    if (c.metric->id() == "colour" || c.weight <= 0) continue;
    log_s += c.weight * std::log(std::max(c.metric->similarity(composite->slice(a.values, k), composite->slice(b, k)), 1e-300));
    weight += c.weight;
  }
  return weight > 0 ? std::exp(log_s / weight) : metric.similarity(a.values, b);
}

int selection_version() { return model::kVersion; }

SelectionTarget::SelectionTarget(const Image& photo, const metrics::Metric& metric) {
  if (metric.id() != model::kMetric || metric.version() != model::kMetricVersion)
    throw Error("the shader selection was fitted on " + std::string(model::kMetric) + " v" +
                    std::to_string(model::kMetricVersion) + " features, not " + metric.id() + " v" +
                    std::to_string(metric.version()),
                "refit it with bench/fit_selection.py (docs/match-evaluation.md)");
  logits_.assign(model::kShaders, -std::numeric_limits<double>::infinity());
  std::vector<double> z(model::kFeatures);
  for (const auto& view : target_views(photo, model::kResolution)) {
    names_.push_back(view.name);
    const auto f = metric.features(view.image, model::kResolution);
    size_t at = 0;
    for (const auto& range : model::kRanges)
      for (size_t i = range[0]; i < range[1]; ++i, ++at) z[at] = (f.values.at(i) - model::kMean[at]) / model::kScale[at];
    for (size_t k = 0; k < model::kShaders; ++k) {
      double logit = model::kBias[k];
      for (size_t i = 0; i < model::kFeatures; ++i) logit += z[i] * model::kWeights[i * model::kShaders + k];
      logits_[k] = std::max(logits_[k], logit);
    }
  }
}

std::vector<double> SelectionTarget::probabilities(const std::vector<std::string>& shaders,
                                                   const std::vector<double>& best_structural) const {
  const double lowest = *std::min_element(logits_.begin(), logits_.end());
  std::vector<double> logit;
  for (const auto& name : shaders) {
    const auto* end = model::kShaderNames + model::kShaders;
    const auto* it = std::find_if(model::kShaderNames, end, [&](const char* n) { return name == n; });
    logit.push_back(it == end ? lowest : logits_[it - model::kShaderNames]);
    logit.back() += model::kStructuralWeight * std::log(std::max(best_structural.at(logit.size() - 1), 1e-6));
  }
  if (logit.empty()) return {};
  const double top = *std::max_element(logit.begin(), logit.end());
  double total = 0;
  for (double& l : logit) total += (l = std::exp(l - top));
  for (double& l : logit) l /= total;
  return logit;
}

}  // namespace proctex::search
