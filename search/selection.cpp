#include "search/selection.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "search/selection_weights.h"

namespace proctex::search {

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

const SelectionModel& default_selection() {
  static const SelectionModel model = [] {
    SelectionModel m;
    m.version = selection::kVersion;
    for (const auto& g : selection::kGroups) m.group_scale.push_back(g.weight / g.median);
    m.view_penalty.assign(std::begin(selection::kViewPenalty), std::end(selection::kViewPenalty));
    m.temperature = selection::kTemperature;
    return m;
  }();
  return model;
}

SelectionTarget::SelectionTarget(const Image& photo, const metrics::Metric& metric, int resolution,
                                 const SelectionModel& model)
    : metric_(metric), model_(model) {
  if (metric.group_count() != model.group_scale.size())
    throw Error("the shader selection was fitted for " + std::to_string(model.group_scale.size()) +
                    " feature groups, the metric '" + metric.id() + "' has " + std::to_string(metric.group_count()),
                "refit it: bench/fit_selection.py");
  for (auto& view : target_views(photo, resolution)) {
    if (names_.size() >= model.view_penalty.size()) break;
    names_.push_back(view.name);
    views_.push_back(metric.features(view.image, resolution));
  }
}

double SelectionTarget::distance(std::span<const float> sample, int* view) const {
  double groups[64];
  const size_t n = model_.group_scale.size();
  if (n > 64) throw Error("too many feature groups for the selection");
  double best = std::numeric_limits<double>::infinity();
  for (size_t v = 0; v < views_.size(); ++v) {
    metric_.group_distances(views_[v].values, sample, groups);
    double d = model_.view_penalty[v];
    for (size_t g = 0; g < n; ++g) d += model_.group_scale[g] * groups[g];
    if (d < best) {
      best = d;
      if (view) *view = static_cast<int>(v);
    }
  }
  return best;
}

std::vector<double> selection_probabilities(const std::vector<double>& distances, const SelectionModel& model) {
  if (distances.empty()) return {};
  const double lowest = *std::min_element(distances.begin(), distances.end());
  std::vector<double> p;
  double total = 0;
  for (double d : distances) {
    p.push_back(std::exp(-(d - lowest) / model.temperature));
    total += p.back();
  }
  for (double& x : p) x /= total;
  return p;
}

}  // namespace proctex::search
