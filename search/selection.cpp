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
  return composite->similarity_without(a.values, b, "colour");
}

std::vector<double> colour_statistics(const Image& photo) {
  const Image square = center_crop_square(photo);
  const size_t n = static_cast<size_t>(square.width) * square.height;
  std::vector<float> channel[4];  // L*, a*, b*, C*
  for (auto& c : channel) c.resize(n);
  double hue_cos = 0, hue_sin = 0, chroma_total = 0;
  auto f = [](double t) { return t > 216.0 / 24389.0 ? std::cbrt(t) : (24389.0 / 27.0 * t + 16.0) / 116.0; };
  for (size_t i = 0; i < n; ++i) {
    const float* p = square.pixels.data() + 3 * i;
    const double r = std::max(0.0f, p[0]), g = std::max(0.0f, p[1]), b = std::max(0.0f, p[2]);
    // linear sRGB -> XYZ (D65), normalised by the white point
    const double x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047;
    const double y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
    const double z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883;
    const double fx = f(x), fy = f(y), fz = f(z);
    const double L = 116.0 * fy - 16.0, A = 500.0 * (fx - fy), B = 200.0 * (fy - fz);
    const double C = std::hypot(A, B);
    channel[0][i] = static_cast<float>(L);
    channel[1][i] = static_cast<float>(A);
    channel[2][i] = static_cast<float>(B);
    channel[3][i] = static_cast<float>(C);
    hue_cos += A;  // = C cos(h): chroma-weighted
    hue_sin += B;
    chroma_total += C;
  }
  std::vector<double> out;
  for (auto& c : channel) {
    double mean = 0, sq = 0;
    for (float v : c) mean += v;
    mean /= static_cast<double>(n);
    for (float v : c) sq += (v - mean) * (v - mean);
    out.push_back(mean);
    out.push_back(std::sqrt(sq / static_cast<double>(n)));
  }
  for (auto& c : channel) {
    for (double q : {0.1, 0.5, 0.9}) {
      const auto at = c.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(n - 1));
      std::nth_element(c.begin(), at, c.end());
      out.push_back(*at);
    }
  }
  out.push_back(chroma_total > 0 ? hue_cos / chroma_total : 0.0);
  out.push_back(chroma_total > 0 ? hue_sin / chroma_total : 0.0);
  return out;
}

double shape_distance(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != kShapeStatistics || b.size() != kShapeStatistics)
    throw Error("shape statistics of different lengths", "an internal error: report it");
  // The model's shape statistics (v6 and later) come after the metric's features and before the
  // micro statistics (v9 and later); without them the raw values count alike.
  const size_t first = model::kFeatures - model::kShapeFeatures - model::kMicroFeatures;
  double sum = 0;
  for (size_t i = 0; i < kShapeStatistics; ++i) {
    const double scale = model::kShapeFeatures > 0 ? double(model::kScale[first + i]) : 1.0;
    const double d = (a[i] - b[i]) / scale;
    sum += d * d;
  }
  return std::sqrt(sum / double(kShapeStatistics));
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
    // Then the view's shape statistics (none before v6) and its micro-structure (none before v9).
    static_assert(model::kShapeFeatures == 0 || model::kShapeFeatures == kShapeStatistics,
                  "selection model and shape_statistics disagree");
    static_assert(model::kMicroFeatures == 0 || model::kMicroFeatures == kMicroStatistics,
                  "selection model and micro_statistics disagree");
    if (model::kShapeFeatures > 0) {
      const auto shape = shape_statistics(view.image, model::kResolution);
      for (size_t i = 0; i < model::kShapeFeatures; ++i, ++at) z[at] = (shape[i] - model::kMean[at]) / model::kScale[at];
    }
    if (model::kMicroFeatures > 0) {
      const auto micro = micro_statistics(view.image, model::kResolution);
      for (size_t i = 0; i < model::kMicroFeatures; ++i, ++at) z[at] = (micro[i] - model::kMean[at]) / model::kScale[at];
    }
    for (size_t k = 0; k < model::kShaders; ++k) {
      double logit = model::kBias[k];
      for (size_t i = 0; i < model::kFeatures; ++i) logit += z[i] * model::kWeights[i * model::kShaders + k];
      logits_[k] = std::max(logits_[k], logit);
    }
  }
  // Calibration: the structural logits divided by their temperature, the colour logits by theirs.
  for (double& l : logits_) l /= model::kStructuralTemperature;
  // The colour term: the same for every view (colour statistics of the whole photo).
  static_assert(model::kColourFeatures == kColourStatistics, "selection model and colour_statistics disagree");
  const auto stats = colour_statistics(photo);
  const bool greyscale = stats[6] < kGreyscaleChroma;  // [6]: mean chroma
  for (size_t c = 0; c < (greyscale ? 0 : model::kColourFeatures); ++c) {
    const double zc = (stats[c] - model::kColourMean[c]) / model::kColourScale[c];
    for (size_t k = 0; k < model::kShaders; ++k)
      logits_[k] += zc * model::kColourWeights[c * model::kShaders + k] / model::kColourTemperature;
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
