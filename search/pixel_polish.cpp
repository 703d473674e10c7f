#include "search/pixel_polish.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <set>
#include <random>
#include <stdexcept>
#include <tuple>

#include <nlopt.hpp>

#include "metrics/aligned.h"
#include "metrics/pixels.h"
#include "search/colour_fit.h"
#include "search/objective.h"
#include "search/refine.h"
#include "shaders/parameter_space.h"

namespace proctex::search {
namespace {

struct Start {
  std::string name;
  std::vector<float> packed;
};

// The point as found and its colour-swapped variants, when the shader has exactly two searchable
// colours (a two-colour pattern: stripes, checker, chevron, swirl; for a shape's fg/bg the swap
// simply loses). A `duty` in [min, max] is complemented too: duty d in colours (a, b) is the same
// pattern as 1 - d in (b, a), up to where the period starts.
std::vector<Start> polish_starts(const ShaderDecl& decl, const std::vector<float>& packed,
                                 const std::vector<std::string>& pinned) {
  std::vector<Start> starts = {{"as found", packed}};
  const auto is_pinned = [&](const std::string& n) { return std::find(pinned.begin(), pinned.end(), n) != pinned.end(); };
  std::vector<const ParamDecl*> colours;
  for (const auto& p : decl.params)
    if (p.type == ParamType::Color && p.searchable && !is_pinned(p.name)) colours.push_back(&p);
  if (colours.size() != 2) return starts;
  std::vector<float> swapped = packed;
  for (int c = 0; c < 3; ++c) std::swap(swapped[colours[0]->offset + c], swapped[colours[1]->offset + c]);
  starts.push_back({"colours swapped", swapped});
  const ParamDecl* duty = decl.find("duty");
  if (duty && duty->type == ParamType::Float && duty->searchable && !is_pinned("duty")) {
    std::vector<float> complemented = swapped;
    complemented[duty->offset] = duty->min + duty->max - complemented[duty->offset];
    starts.push_back({"colours swapped, duty complemented", complemented});
  }
  return starts;
}


// The RGB RMS difference of `packed`'s render against the target's features for its registration
// (PixelMetric::target_features; one render).
double render_rmse(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                   const metrics::PixelMetric& pixels, const metrics::Features& target, Renderer& renderer) {
  RenderSettings settings;
  settings.width = settings.height = pixels.size();
  const Image render = renderer.render_batch(decl, {packed}, std::vector<uint32_t>{seed}, settings).front();
  return std::sqrt(pixels.distance(target.values, pixels.features(render, pixels.size()).values));
}

struct ProjectedContext {
  const ShaderDecl* decl;
  const ParameterSpace* shape;
  uint32_t seed;
  const std::vector<std::string>* pinned;
  const std::vector<float>* wanted;
  const std::vector<uint8_t>* mask;
  int side;
  Renderer* renderer;
  long renders = 0, budget = 0;
  double best_mse = 1e300;
  std::vector<float> best_packed;
  bool zero_offset = false;  // fit_colours_to_pixels: the first fit's offset render was black
};

double projected_objective(unsigned n, const double* x, double*, void* data) {
  auto& c = *static_cast<ProjectedContext*>(data);
  if (c.renders >= c.budget) throw nlopt::forced_stop();
  const auto fit = fit_colours_to_pixels(*c.decl, c.shape->to_packed(std::vector<double>(x, x + n)), c.seed, *c.pinned,
                                         *c.wanted, *c.mask, c.side, *c.renderer, ColourBounds::Bounded, c.zero_offset);
  c.renders += fit.renders;
  // A shader that mixes its colours renders black with them all black, whatever its shape: the
  // offset render is skipped from then on (the polished end point is checked by a render).
  if (c.renders == fit.renders) c.zero_offset = fit.offset_black;
  if (fit.mse < c.best_mse) {
    c.best_mse = fit.mse;
    c.best_packed = fit.packed;
  }
  return fit.mse;
}

// Line scans across the whole range of each shape parameter whose basin is broad (its probed step
// was not cut), the others held, for up to two passes: a duty and an edge softness trade along a
// valley that BOBYQA follows only to a near-miss (a chevron's duty 0.38 and softness 0.90 for 0.49
// and 0.46, RMS 0.003; wavy stripes at RMS 0.03), while one parameter swept whole finds the other
// side of the trade. Sensitive parameters (an angle, a twist, a wave frequency) are left to BOBYQA:
// a coarse sweep never lands inside their basin.
constexpr int kScanLevels = 16;
constexpr double kScanAboveRmse = 5e-4;  // a polished start this close is left to BOBYQA
constexpr int kScanPasses = 3;
void scan_broad_dimensions(unsigned n, const std::vector<double>& steps, ProjectedContext& c) {
  for (int pass = 0; pass < kScanPasses; ++pass) {
    bool moved = false;
    for (unsigned d = 0; d < n; ++d) {
      if (steps[d] < 0.002) continue;
      const double before = c.best_mse;
      std::vector<double> x = c.shape->to_unit(c.best_packed);
      for (int k = 0; k < kScanLevels; ++k) {
        x[d] = double(k) / (kScanLevels - 1);
        projected_objective(n, x.data(), nullptr, &c);
      }
      moved = moved || c.best_mse < before * 0.98;
    }
    if (!moved) return;
  }
}

// Variable projection: the shape's continuous parameters by BOBYQA, the colours solved by least
// squares for each shape (colour_fit.h). Softness, duty and colour trade against each other in a
// long narrow valley when searched together (a 15-arm swirl moved 0.004 -> 0.0013 RMS in 500
// renders and still had its softness 3% off); with the colours projected out the valley is gone.
// Requires a shader linear in its colours; the caller checks the model against a render.
std::vector<float> projected_polish(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                                    const std::vector<std::string>& pinned, const std::vector<std::string>& shape_pinned,
                                    const std::vector<float>& wanted, const std::vector<uint8_t>& mask, int side,
                                    Renderer& renderer, long budget, long& used, bool scan = true) {
  const ParameterSpace shape(decl, packed, shape_pinned);
  ProjectedContext c{&decl, &shape, seed, &pinned, &wanted, &mask, side, &renderer, 0, 0, 1e300, {}};
  c.budget = budget;
  std::vector<double> x = shape.to_unit(packed);
  const unsigned n = static_cast<unsigned>(x.size());
  const double start_mse = projected_objective(n, x.data(), nullptr, &c);
  // A step per dimension that stays inside the basin: from 0.2% of the range, quartered while a
  // step more than doubles the difference (a 15-arm swirl's twist needs 1e-4 of its range, its
  // softness 100x more). BOBYQA scales its model by these steps.
  std::vector<double> steps(n, 0.002);
  try {
    for (unsigned d = 0; d < n; ++d) {
      for (int k = 0; k < 5; ++k) {
        std::vector<double> probe = x;
        probe[d] = x[d] + (x[d] + steps[d] <= 1.0 ? steps[d] : -steps[d]);
        if (projected_objective(n, probe.data(), nullptr, &c) <= 2.0 * start_mse + 1e-9) break;
        steps[d] *= 0.25;
      }
    }
  } catch (const nlopt::forced_stop&) {
  }
  const auto bobyqa = [&](long cap) {
    const long budget_before = c.budget;
    c.budget = std::min(c.budget, c.renders + cap);
    for (int pass = 0; pass < 4 && shape.dimensions() > 0 && c.renders < c.budget; ++pass) {
      const double before = c.best_mse;
      nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(x.size()));
      opt.set_lower_bounds(std::vector<double>(x.size(), 0.0));
      opt.set_upper_bounds(std::vector<double>(x.size(), 1.0));
      opt.set_initial_step(steps);
      opt.set_xtol_abs(1e-7);
      opt.set_ftol_abs(1e-12);
      opt.set_min_objective(projected_objective, &c);
      x = shape.to_unit(c.best_packed);
      double f = 0;
      try {
        opt.optimize(x, f);
      } catch (const nlopt::forced_stop&) {
      } catch (const nlopt::roundoff_limited&) {
      } catch (const std::invalid_argument&) {  // a start on a bound with a step across it
      }
      if (before - c.best_mse < 1e-10) break;
    }
    c.budget = budget_before;
  };
  // The local search first, with a third of the renders: from a start near the truth it ends exact, and
  // a scan could leave that basin for a lower point of another valley (a grid's sub-pixel minor
  // lines trade width for strength). Only a start that stays visibly off is scanned.
  bobyqa(budget / 3);
  if (scan && std::sqrt(c.best_mse) > kScanAboveRmse && c.renders < c.budget) {
    try {
      scan_broad_dimensions(n, steps, c);
    } catch (const nlopt::forced_stop&) {
    }
  }
  bobyqa(budget);
  used += c.renders;
  return c.best_packed;
}

// All continuous parameters, colours included, by BOBYQA on the plain pixel difference: for a
// shader whose colours are not linear (its basis would lie).
std::vector<float> joint_polish(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                                const std::vector<std::string>& kept, const metrics::PixelMetric& pixels,
                                const metrics::Features& target_features, Renderer& renderer, long budget,
                                long& used) {
  const int side = pixels.size();
  const ParameterSpace space(decl, packed, kept);
  if (space.dimensions() == 0) return packed;
  Objective objective(space, target_features, pixels, renderer, seed, side);
  objective.set_budget({budget, 0.0});
  RefineOptions options;
  options.optimizer = Optimizer::Bobyqa;
  options.initial_step = 0.002;
  options.tolerance = 1e-9;
  options.max_restarts = 10;
  options.max_evaluations = budget;
  options.probe_bounds = false;
  const auto r = refine(objective, space.to_unit(packed), options);
  used += objective.evaluations();
  return space.to_packed(r.unit);
}

// The parameters a shape-only search keeps: `kept` and every colour (the colours are projected out).
std::vector<std::string> shape_pinned_of(const ShaderDecl& decl, const std::vector<std::string>& kept) {
  std::vector<std::string> shape_pinned = kept;
  for (const auto& p : decl.params)
    if (p.type == ParamType::Color) shape_pinned.push_back(p.name);
  return shape_pinned;
}

// One start polished at its registration: projected when the shader's colours are linear (the
// colour model reproduces the render), jointly otherwise. Returns the end point and its RMS (from
// a render), never worse than the start.
std::pair<std::vector<float>, double> polish_start(const ShaderDecl& decl, const std::vector<float>& packed,
                                                   uint32_t seed, const std::vector<std::string>& pinned,
                                                   const std::vector<std::string>& kept, const Image& target, int dx,
                                                   int dy, Renderer& renderer, long budget, long& used,
                                                   nlohmann::json& entry, bool scan = true) {
  const int side = target.width;
  std::vector<uint8_t> mask;
  const auto wanted = metrics::moved_target(target, dx, dy, mask);
  const metrics::PixelMetric pixels(side);
  const metrics::Features target_features = pixels.target_features(target, dx, dy);
  const double start_rmse = render_rmse(decl, packed, seed, pixels, target_features, renderer);
  used += 1;
  const std::vector<std::string> shape_pinned = shape_pinned_of(decl, kept);
  // Is the colour model exact here? Fit once and compare its residual with a render's.
  const auto first = fit_colours_to_pixels(decl, packed, seed, pinned, wanted, mask, side, renderer, ColourBounds::Bounded);
  const double first_rmse = render_rmse(decl, first.packed, seed, pixels, target_features, renderer);
  used += first.renders + 1;
  const bool linear = std::fabs(first_rmse - std::sqrt(first.mse)) <= 1e-4 + 0.01 * first_rmse;
  entry["method"] = linear ? "colours projected" : "joint";
  std::vector<float> end =
      linear ? projected_polish(decl, first.packed, seed, pinned, shape_pinned, wanted, mask, side, renderer,
                                std::max<long>(0, budget - used), used, scan)
             : joint_polish(decl, packed, seed, kept, pixels, target_features, renderer, std::max<long>(0, budget - used), used);
  double end_rmse = render_rmse(decl, end, seed, pixels, target_features, renderer);
  used += 1;
  if (first_rmse < end_rmse) {
    end = first.packed;
    end_rmse = first_rmse;
  }
  if (start_rmse < end_rmse) return {packed, start_rmse};
  return {end, end_rmse};
}

// The count hop: the polish keeps counts, and a small spiky star (50 px across) polished with 3
// points for the target's 6 stays there (RMS 0.011; synthetic target 43 of session 21, answered
// with 7). For each count that divides a searched rotation's declared period (shader.h
// `period=P/COUNT`), every other count of its range with the rotation at kHopCountPhases phases of
// the new period (the found rotation fits the new count's points only by chance) is judged after a
// least-squares colour fit (the colours + 1 renders each: 162 renders for a star); the closest gets
// a hop's local search (the star: 6 points at RMS 0.0005, polished to 1e-5). Returns whether it
// landed lower than `best`.
bool hop_counts(const ShaderDecl& decl, uint32_t seed, const std::vector<std::string>& pinned,
                const std::vector<std::string>& kept, const Image& target, Renderer& renderer, long max_evaluations,
                PixelPolishResult& best, nlohmann::json& hops) {
  const auto is_pinned = [&](const std::string& n) { return std::find(pinned.begin(), pinned.end(), n) != pinned.end(); };
  std::vector<uint8_t> mask;
  const auto wanted = metrics::moved_target(target, best.dx, best.dy, mask);
  bool lower = false;
  for (const auto& rotation : decl.params) {
    if (rotation.period_per.empty() || !rotation.searchable || is_pinned(rotation.name) ||
        is_pinned(rotation.period_per))
      continue;
    const ParamDecl& count = *decl.find(rotation.period_per);
    if (!count.searchable) continue;
    const int n = static_cast<int>(std::lround(best.packed[count.offset]));
    std::vector<float> closest;
    double closest_mse = 0.0;
    for (int m = static_cast<int>(count.min); m <= static_cast<int>(count.max); ++m) {
      if (m == n) continue;
      for (int k = 0; k < kHopCountPhases; ++k) {
        if (max_evaluations - best.evaluations < kHopEvaluations) return lower;
        std::vector<float> moved = best.packed;
        moved[count.offset] = static_cast<float>(m);
        moved[rotation.offset] += static_cast<float>(k * rotation.period / m / kHopCountPhases);
        moved = canonical_packed(decl, moved);
        const auto fit = fit_colours_to_pixels(decl, moved, seed, pinned, wanted, mask, target.width, renderer,
                                               ColourBounds::Bounded);
        best.evaluations += fit.renders;
        if (closest.empty() || fit.mse < closest_mse) {
          closest = fit.packed;
          closest_mse = fit.mse;
        }
      }
    }
    if (closest.empty() || max_evaluations - best.evaluations < kHopEvaluations) continue;
    nlohmann::json entry = {{"count", count.name},
                            {"to", std::lround(closest[count.offset])},
                            {"rmse_before", std::sqrt(closest_mse)}};
    long used = 0;
    const auto [end, rmse] = polish_start(decl, closest, seed, pinned, kept, target, best.dx, best.dy, renderer,
                                          kHopEvaluations, used, entry, false);
    best.evaluations += used;
    entry["rmse_after"] = rmse;
    hops.push_back(entry);
    if (rmse < best.rmse) {
      best.packed = end;
      best.rmse = rmse;
      lower = true;
    }
  }
  return lower;
}

// Basin hopping: a polished point that still misses the target's pixels sits in a local minimum
// of their difference, one the starts above do not leave - a superellipse turned 45 degrees with its
// exponent traded for the turn (RMS 0.046); a soft ring polished to a tent, its blur wider than its
// band, where the target's band has a flat top (RMS 0.009; every point on the straight line to the
// truth is worse until the regime changes). Each hop moves the shape parameters and gives the move
// a short local search; a move that ends lower becomes the point the next hop leaves from. First
// every other value of a count that divides a rotation's period (hop_counts), then a
// parameter stopped at an end of its range is carried across a declared exchange (shader.h), then
// each parameter alone goes to the other half of its range (half a turn of a rotation), then all of
// them at random within a radius that grows from hop to hop (a fixed seed: the same answer every run).
// A hop that lands clearly lower is polished on before the next move.
void hop_between_basins(const ShaderDecl& decl, uint32_t seed, const std::vector<std::string>& pinned,
                        const std::vector<std::string>& kept, const Image& target, Renderer& renderer,
                        long max_evaluations, PixelPolishResult& best, nlohmann::json& report) {
  if (best.rmse < kHopAboveRmse || best.rmse > kPixelPolishStartRmse) return;
  const std::vector<std::string> shape_pinned = shape_pinned_of(decl, kept);
  const int dims = ParameterSpace(decl, best.packed, shape_pinned).dimensions();
  if (dims == 0) return;
  const auto is_kept = [&](const std::string& n) { return std::find(kept.begin(), kept.end(), n) != kept.end(); };
  std::mt19937 random(kHopSeed);
  const auto uniform = [&] { return double(random()) / 4294967296.0; };
  static constexpr double kRadii[] = {0.05, 0.15, 0.3, 0.5};
  nlohmann::json hops = nlohmann::json::array();
  bool hopped = hop_counts(decl, seed, pinned, kept, target, renderer, max_evaluations, best, hops);
  bool continue_last = hopped;  // a count hop that landed lower is polished on first
  // Hops 0 .. dims-1: across a declared exchange (shader.h), then dims .. 2 dims-1: to the other
  // half, then at random. An exchange move that does not apply (the parameter away from its ends,
  // or an exchanged parameter pinned) is skipped without a render.
  // A hop needs its whole allowance; the continuation of one that landed lower takes what is left.
  const auto affordable = [&] {
    const long left = max_evaluations - best.evaluations;
    return left >= kHopEvaluations || (continue_last && left >= kHopEvaluations / 4);
  };
  for (int hop = 0; best.rmse >= kHopAboveRmse && affordable();) {
    const ParameterSpace shape(decl, best.packed, shape_pinned);
    auto unit = shape.to_unit(best.packed);
    std::vector<float> moved;
    nlohmann::json entry;
    if (continue_last) {
      entry["continued"] = true;  // the last hop landed lower: its local search goes on first
    } else if (const int h = hop++; h < dims) {
      const ParamDecl& p = *shape.dims()[h].param;
      const double u = unit[h];
      if (p.exchange.empty() || is_kept(p.exchange[0]) || is_kept(p.exchange[1]) ||
          (u > kHopExchangeEnd && u < 1.0 - kHopExchangeEnd))
        continue;
      // The point seen from the other end (the same image, up to the few hundredths of the range
      // it was short of its end): the local search can now go on past the end it was stopped at
      // (a superellipse at 0 degrees for the target's 82).
      moved = best.packed;
      moved[p.offset] = u < 0.5 ? p.max : p.min;
      std::swap(moved[decl.find(p.exchange[0])->offset], moved[decl.find(p.exchange[1])->offset]);
      entry["exchanged"] = p.name;
    } else if (h < 2 * dims) {
      unit[h - dims] = std::fmod(unit[h - dims] + 0.5, 1.0);
      entry["moved"] = shape.dims()[h - dims].param->name;
    } else {
      const double radius = kRadii[(h - 2 * dims) % std::size(kRadii)];
      for (double& u : unit) u = std::clamp(u + radius * (2.0 * uniform() - 1.0), 0.0, 1.0);
      entry["radius"] = radius;
    }
    if (moved.empty()) moved = shape.to_packed(unit);
    long used = 0;
    const auto [end, rmse] = polish_start(decl, moved, seed, pinned, kept, target, best.dx, best.dy, renderer,
                                          std::min(kHopEvaluations, max_evaluations - best.evaluations), used, entry,
                                          false);
    best.evaluations += used;
    entry["rmse_after"] = rmse;
    hops.push_back(entry);
    continue_last = rmse < kHopContinueShare * best.rmse;
    if (rmse < best.rmse) {
      best.packed = end;
      best.rmse = rmse;
      hopped = true;
    }
  }
  if (hops.empty()) return;
  if (hopped) best.start += ", hopped";
  report.push_back({{"start", "hops"}, {"hops", hops}, {"rmse_after", best.rmse}});
}

}  // namespace

double flat_rmse(const Image& image) {
  const size_t n = static_cast<size_t>(image.width) * image.height;
  if (n == 0) return 0.0;
  double mean[3] = {0, 0, 0}, squares = 0;
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) mean[c] += image.pixels[3 * i + c];
  for (double& m : mean) m /= static_cast<double>(n);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = image.pixels[3 * i + c] - mean[c];
      squares += d * d;
    }
  return std::sqrt(squares / (3.0 * static_cast<double>(n)));
}

PixelPolishResult pixel_polish(const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed,
                               const std::vector<std::string>& pinned, const Image& target, Renderer& renderer,
                               long max_evaluations, nlohmann::json& report) {
  PixelPolishResult best;
  const int side = target.width;
  RenderSettings settings;
  settings.width = settings.height = side;
  std::vector<std::string> kept = pinned;
  for (const auto& p : decl.params)
    if (p.discrete()) kept.push_back(p.name);
  const auto starts = polish_starts(decl, packed, pinned);
  std::vector<Image> renders;
  {
    std::vector<std::vector<float>> points;
    for (const auto& s : starts) points.push_back(s.packed);
    renders = renderer.render_batch(decl, points, std::vector<uint32_t>(points.size(), seed), settings);
    best.evaluations += static_cast<long>(points.size());
  }
  // Each start at its best registration and, when that is elsewhere, at the shader's own origin:
  // a pattern periodic along a direction (stripes) registers almost as well at many shifts, and
  // only at the origin can its parameters be the target's.
  struct Candidate {
    size_t start;
    metrics::AlignedMetric::Registration at;
  };
  std::vector<Candidate> candidates;
  const metrics::PixelMetric pixels(side);
  const auto unshifted = pixels.target_features(target, 0, 0);
  for (size_t i = 0; i < starts.size(); ++i) {
    const auto reg = metrics::AlignedMetric::register_rgb(target, renders[i]);
    candidates.push_back({i, reg});
    if (reg.dx != 0 || reg.dy != 0)
      candidates.push_back({i, {std::sqrt(pixels.distance(unshifted.values, pixels.features(renders[i], side).values)), 0, 0}});
  }
  // A start judged in its own colours at the origin can look far (RMS 0.2) when only its colours
  // are off there - the registration that found it matched another phase, and a swap of the two
  // colours is not the only relation between their phases (a chevron's duty and softness trade):
  // at the origin it is then judged after a least-squares colour fit.
  std::vector<uint8_t> origin_mask;
  const auto origin_wanted = metrics::moved_target(target, 0, 0, origin_mask);
  for (auto& candidate : candidates) {
    if (candidate.at.dx != 0 || candidate.at.dy != 0 || candidate.at.rmse <= kPixelPolishStartRmse) continue;
    const auto fit = fit_colours_to_pixels(decl, starts[candidate.start].packed, seed, pinned, origin_wanted,
                                           origin_mask, side, renderer);
    best.evaluations += fit.renders;
    candidate.at.rmse = std::min(candidate.at.rmse, std::sqrt(fit.mse));
  }
  // At the origin first (only there can the parameters be the target's, and a start exact there
  // ends the polish), then closest first: the budget goes where the pixels already agree.
  std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    const bool a0 = a.at.dx == 0 && a.at.dy == 0, b0 = b.at.dx == 0 && b.at.dy == 0;
    return a0 != b0 ? a0 : a.at.rmse < b.at.rmse;
  });
  report = nlohmann::json::array();
  const auto shift = [](int dx, int dy) { return std::abs(dx) + std::abs(dy); };
  // With the colours projected out a start is its shape: two starts that differ only in their
  // colours (the point as found and its colours swapped) at one registration polish alike.
  const auto shape_of = [&](const std::vector<float>& packed) {
    std::vector<float> shape = packed;
    for (const auto& p : decl.params)
      if (p.type == ParamType::Color)
        for (int c = 0; c < 3; ++c) shape[p.offset + c] = 0.0f;
    return shape;
  };
  std::set<std::tuple<std::vector<float>, int, int>> projected_done;
  const double flat_limit = kPixelPolishFlatShare * flat_rmse(target);
  for (const auto& [i, reg] : candidates) {
    // Exact at the origin already: nothing left to find.
    if (best.rmse >= 0 && best.rmse < kExactAtOriginRmse && shift(best.dx, best.dy) == 0) break;
    nlohmann::json entry = {{"start", starts[i].name}, {"rmse_before", reg.rmse}, {"shift", {reg.dx, reg.dy}}};
    const auto key = std::make_tuple(shape_of(starts[i].packed), reg.dx, reg.dy);
    const bool at_origin = reg.dx == 0 && reg.dy == 0;
    if (reg.rmse > std::min(at_origin ? kPixelPolishOriginStartRmse : kPixelPolishStartRmse, flat_limit) ||
        best.evaluations >= max_evaluations || projected_done.count(key)) {
      if (projected_done.count(key)) entry["same_shape_as_an_earlier_start"] = true;
      report.push_back(entry);
      continue;
    }
    const long budget = std::min(kPixelPolishEvaluations, max_evaluations - best.evaluations);
    long used = 0;
    const auto [end, rmse] = polish_start(decl, starts[i].packed, seed, pinned, kept, target, reg.dx, reg.dy, renderer,
                                          budget, used, entry);
    best.evaluations += used;
    if (entry.value("method", "") == "colours projected") projected_done.insert(key);
    entry["rmse_after"] = rmse;
    report.push_back(entry);
    const bool better = best.rmse < 0 || rmse < best.rmse - 1e-4 ||
                        (rmse <= best.rmse + 1e-4 && shift(reg.dx, reg.dy) < shift(best.dx, best.dy));
    if (better) {
      best.packed = end;
      best.rmse = rmse;
      best.dx = reg.dx;
      best.dy = reg.dy;
      best.start = starts[i].name;
    }
  }
  hop_between_basins(decl, seed, pinned, kept, target, renderer, max_evaluations, best, report);
  return best;
}

}  // namespace proctex::search
