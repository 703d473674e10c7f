#include "search/align.h"

#include <algorithm>
#include <cmath>

#include "search/objective.h"
#include "search/pixel_polish.h"

namespace proctex::search {

AlignStages align_stages(const Image& target, int resolution) {
  AlignStages out;
  const std::vector<std::pair<int, std::pair<double, double>>> plan = {
      {8, {0.4, 0.05}}, {4, {0.3, 0.01}}, {2, {0.3, 0.003}}};
  for (const auto& [factor, rest] : plan) {
    if (resolution % factor != 0 || resolution / factor < 16) continue;
    const metrics::AlignedMetric m(resolution / factor);
    out.stages.push_back({m, m.features(target, resolution), rest.first, rest.second});
  }
  if (!out.stages.empty()) {
    // At least 64 px: the smallest analysis the metrics support (a 128 px match's first stage is 16).
    out.scan_resolution = std::min(resolution, std::max(64, 2 * out.stages.front().metric.size()));
    out.scan_target = out.stages.front().metric.features(target, out.scan_resolution);
  }
  return out;
}

long align_rescue_renders(const ParameterSpace& space) {
  long continuous = 0;
  for (const auto& d : space.dims())
    if (!d.levels && d.param->type == ParamType::Float) ++continuous;
  return 1 + long(kAlignRescueLevels) * kAlignRescueRounds * continuous + kAlignEvaluations + 1;
}

namespace {

// Whether a similarity on `metric` is farther from the target than kPixelPolishStartRmse.
bool align_missed_at(const metrics::AlignedMetric& metric, double similarity) {
  return -metric.scale() * std::log(std::max(similarity, 1e-300)) > kPixelPolishStartRmse;
}

}  // namespace

bool align_missed(const AlignStages& stages, double similarity) {
  return !stages.stages.empty() && align_missed_at(stages.stages.back().metric, similarity);
}

namespace {

RefineResult run_stages(const ParameterSpace& space, const std::vector<std::vector<double>>& starts,
                        const std::vector<AlignStage>& stages, Renderer& renderer, uint32_t seed, int resolution,
                        const RefineOptions& base, long& evaluations) {
  RefineResult r;
  r.unit = starts.front();
  for (size_t k = 0; k < stages.size(); ++k) {
    const long budget = std::max<long>(2, long(kAlignEvaluations * stages[k].share));
    Objective objective(space, stages[k].target, stages[k].metric, renderer, seed, resolution);
    objective.set_budget({budget, 0.0});
    std::vector<double> from = r.unit;
    if (k == 0) {
      const auto scores = objective.evaluate(starts);
      from = starts[std::max_element(scores.begin(), scores.end()) - scores.begin()];
    }
    RefineOptions options = base;
    options.initial_step = stages[k].initial_step;
    options.max_evaluations = std::max<long>(1, budget - objective.evaluations());
    r = refine(objective, from, options);
    evaluations += objective.evaluations();
  }
  return r;
}

}  // namespace

RefineResult align_pattern(const ParameterSpace& space, const std::vector<std::vector<double>>& starts,
                           const AlignStages& stages, Renderer& renderer, uint32_t seed, int resolution,
                           const RefineOptions& base, long& evaluations, bool rescue, nlohmann::json* report) {
  RefineResult r = run_stages(space, starts, stages.stages, renderer, seed, resolution, base, evaluations);
  if (!rescue || stages.stages.empty() || !align_missed(stages, r.similarity)) return r;
  // The rescue: a line scan on the coarsest stage from the caller's first start (the point as
  // found), then the stages again from what it finds. Not from the start the first stage picked nor
  // from the end point: far from the target every start scores near 0 and the least wrong is often
  // a mirrored, shrunken shape (a superellipse at width 0.35, height 0.06), from which no single
  // parameter leads anywhere.
  const long before = evaluations;
  Objective coarse(space, stages.scan_target, stages.stages.front().metric, renderer, seed, stages.scan_resolution);
  const double from = coarse.evaluate(starts.front());  // the scan's first render (cached)
  const auto scanned = scan_coordinates(coarse, starts.front(), kAlignRescueLevels, kAlignRescueRounds);
  evaluations += coarse.evaluations();
  // The stages run again only if the scan found another basin: within the pixel polish's reach on
  // its own metric and at most half the start's distance there. Otherwise the scan only confirmed
  // the start (a fine stripe pattern is blurred alike everywhere at this scale: 0.95 -> 0.96, and
  // the stages from there ended where they had) or found nothing (another shader's finalist).
  const auto distance = [&](double similarity) {
    return -stages.stages.front().metric.scale() * std::log(std::max(similarity, 1e-300));
  };
  RefineResult again;
  const bool found = !align_missed_at(stages.stages.front().metric, scanned.similarity) &&
                     distance(scanned.similarity) <= kAlignRescueGain * distance(from);
  if (found) again = run_stages(space, {scanned.unit}, stages.stages, renderer, seed, resolution, base, evaluations);
  const bool kept = found && again.similarity > r.similarity;
  if (report)
    *report = {{"before", r.similarity}, {"scan_from", from}, {"scanned", scanned.similarity},
               {"after", found ? nlohmann::json(again.similarity) : nlohmann::json(nullptr)},
               {"evaluations", evaluations - before}, {"kept", kept}};
  return kept ? again : r;
}

}  // namespace proctex::search
