#include "search/match.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "catalog/store.h"
#include "core/error.h"
#include "core/parallel.h"
#include "kernels/runtime.h"
#include "metrics/composite.h"
#include "metrics/aligned.h"
#include "metrics/magnitude.h"
#include "search/align.h"
#include "search/colour_fit.h"
#include "search/pixel_polish.h"
#include "search/selection.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"

namespace proctex::search {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

struct Start {
  std::string shader;
  const catalog::Sample* sample = nullptr;
  double similarity = 0.0;            // whole metric at the screening resolution, colours fitted
  double catalogue_similarity = 0.0;  // structural, from the stored features
  std::vector<float> packed;          // the sample with fitted colours
  double probability = 0.0;           // selection probability of the shader
};

struct ShaderScan {
  catalog::ShaderCatalogue catalogue;
  std::vector<double> similarity;  // per sample: structural similarity to the target (see below)
  double best_pruned = 0.0;
  double best_full = 0.0;
  double probability = 0.0;        // selection probability of the shader
};

std::vector<int> parse_crop(const std::string& text) {
  std::vector<int> v;
  std::stringstream in(text);
  std::string part;
  while (std::getline(in, part, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stoi(part, &used));
      if (used != part.size()) throw std::invalid_argument(part);
    } catch (const std::exception&) {
      throw UsageError("--crop '" + text + "' is not x,y,w,h", "write e.g. --crop 100,50,512,512");
    }
  }
  if (v.size() != 4) throw UsageError("--crop '" + text + "' is not x,y,w,h", "write e.g. --crop 100,50,512,512");
  return v;
}

// Checks that the catalogue's features were made by the metric this proctex computes.
void check_metric(const catalog::ShaderSummary& s, const metrics::Metric& metric, int resolution,
                  const std::filesystem::path& db) {
  if (s.metric != metric.id() || s.metric_version != metric.version() || s.resolution != resolution)
    throw Error("catalogue '" + db.string() + "' is stale: shader '" + s.name + "' has " + s.metric + " v" +
                    std::to_string(s.metric_version) + " features at " + std::to_string(s.resolution) +
                    " px, this proctex compares " + metric.id() + " v" + std::to_string(metric.version()) + " at " +
                    std::to_string(resolution) + " px",
                "rebuild it: proctex catalog build --db " + db.string() + " --force");
}

std::vector<catalog::ShaderSummary> usable_shaders(catalog::Store& store, const MatchOptions& o,
                                                   const metrics::Metric& metric) {
  auto all = store.shaders();
  if (all.empty())
    throw Error("catalogue '" + store.path().string() + "' holds no shader",
                "build it first: proctex catalog build --db " + store.path().string());
  std::vector<catalog::ShaderSummary> out;
  for (const auto& name : o.shaders) {
    auto it = std::find_if(all.begin(), all.end(), [&](const auto& s) { return s.name == name; });
    if (it == all.end())
      throw UsageError("shader '" + name + "' is not in catalogue '" + store.path().string() + "'",
                       "build it: proctex catalog build --shaders " + name);
  }
  for (auto& s : all) {
    if (!o.shaders.empty() && std::find(o.shaders.begin(), o.shaders.end(), s.name) == o.shaders.end()) continue;
    if (!ShaderLibrary::builtin().find(s.name)) continue;  // a user's shader no longer on the path
    check_metric(s, metric, o.resolution, store.path());
    out.push_back(std::move(s));
  }
  if (out.empty()) throw Error("no shader of the catalogue is in the shader library", "rebuild the catalogue");
  for (const auto& [name, value] : o.fixed) {
    const bool known = std::any_of(out.begin(), out.end(), [&](const auto& s) {
      return ShaderLibrary::builtin().get(s.name).find(name) != nullptr;
    });
    if (!known)
      throw UsageError("--fix " + name + ": no shader in the search has a parameter '" + name + "'",
                       "see the parameters with: proctex shaders SHADER");
  }
  return out;
}

// The starting points given a short refinement (the race). First the best screened start of each
// of the `selection_lanes` most likely shaders of the selection (`by_selection`, most likely first):
// without a lane the selection's choice could not win however sure it was (the report split lost 6
// right answers that way, docs/match-evaluation.md). Then half of the lanes go to the best
// screened start of each of the structurally closest shaders (`by_structure`, best first): the
// structural scan uses full-resolution features and ranks the target's shader first more often
// than the 64 px screening does (docs/match-evaluation.md), while screening sees colour. The rest
// go to the best screened starts overall. At most `lanes / 4` (at least 1) starts per shader, so
// one shader's near-duplicate samples do not crowd out a second plausible shader; among
// near-equal similarities smoother samples go first (thesis 4.4: faster, better refinement).
std::vector<Start> choose_race(std::vector<Start> screened, const std::vector<std::string>& by_selection,
                               int selection_lanes, const std::vector<std::string>& by_structure, int lanes) {
  std::stable_sort(screened.begin(), screened.end(), [](const Start& a, const Start& b) {
    if (std::fabs(a.similarity - b.similarity) > 0.01) return a.similarity > b.similarity;
    return a.sample->smoothness < b.sample->smoothness;
  });
  const int per_shader = std::max(1, lanes / 4);
  std::map<std::string, int> used;
  std::vector<bool> taken(screened.size(), false);
  std::vector<Start> out;
  auto take = [&](size_t i) {
    taken[i] = true;
    ++used[screened[i].shader];
    out.push_back(screened[i]);
  };
  auto take_best_of = [&](const std::string& shader) {
    if (used[shader] > 0) return;
    for (size_t i = 0; i < screened.size(); ++i)
      if (screened[i].shader == shader) {
        take(i);
        return;
      }
  };
  for (size_t r = 0; r < by_selection.size() && static_cast<int>(r) < selection_lanes; ++r)
    take_best_of(by_selection[r]);
  for (size_t r = 0; r < by_structure.size() && static_cast<int>(r) < lanes / 2; ++r) take_best_of(by_structure[r]);
  for (size_t i = 0; i < screened.size() && static_cast<int>(out.size()) < lanes; ++i)
    if (!taken[i] && used[screened[i].shader] < per_shader) take(i);
  return out;
}

// The packed base vector of a start with --fix values applied, and the names pinned by them.
std::vector<float> apply_fixed(const ShaderDecl& decl, const std::vector<float>& packed,
                               const std::map<std::string, nlohmann::json>& fixed, std::vector<std::string>& pinned) {
  TextureSpec spec = spec_from_packed(decl, packed, 0);
  for (const auto& [name, value] : fixed) {
    if (!decl.find(name)) continue;  // --fix applies to the shaders that have the parameter
    spec.params[name] = value;
    pinned.push_back(name);
  }
  return resolve(decl, spec);
}

// Whether a spec renders (almost) the same image with another seed: a deterministic pattern
// (tilings, shapes, clean bricks; a faint seed-driven grain is allowed). Mean |difference| over
// a 64 px render, linear RGB.
constexpr double kPatternPeakiness = 0.7;
// On a clean pattern whose most similar finalist is deterministic (a shape, a tiling: what no
// photo of a material shows), the selection - a classifier of photographed materials - is weak
// evidence next to the similarity: its weight in the final choice is this share of
// selection_weight. A superellipse target went to `sky` (S 0.24, P 0.36) over a rounded
// `rectangle` (S 0.51, P 0.05). Otherwise it keeps the whole weight (session 20): with the share
// on every clean pattern, photos that the spectrum calls patterns (slate roofs, parquet planks,
// curtains) went to flexible look-alikes (`stone_wall`, `grass`) over a likelier right shader.
constexpr double kPatternSelectionShare = 0.25;
// The final choice's score of a looks-the-same candidate (match.h kLooksTheSameRmse), minus its
// RMS: below a certain match (1e6 + S) and a pixel-exact one (2e6 - RMS), above any decision.
constexpr double kLooksTheSameScore = 5e5;
// The polish of a deterministic pattern: the blurred-magnitude stage's share of the renders, its
// blur (frequency bins at the refinement resolution), and the discrete parameters enumerated
// whole (stripes up to 64, grid cells up to 32: a local search cannot count them).
constexpr double kPolishCoarseShare = 0.4;
constexpr double kPolishBlurBins = 2.0;
constexpr int kPolishSweepLevels = 64;
// The line scan after the magnitude polishes (refine.h scan_coordinates): values per parameter,
// passes, and the local search from its end point.
constexpr int kScanLevels = 48;
constexpr int kScanRounds = 2;
constexpr long kScanRefineEvaluations = 120;
// The exact magnitude's scan also sweeps each count of at most this many values jointly with each
// continuous scalar at this many values (refine.h scan_discrete_pairs; a star's points: 10 x 16 x 4).
constexpr int kPairMaxLevels = 16;
constexpr int kPairLevels = 16;
// Both magnitude scans also sweep each declared dependency (`needs=`) jointly: the gate at this many
// values above its minimum times the dependent parameter at kScanLevels (refine.h
// scan_dependent_pairs; the stripes' wave x wave frequency: 8 x 48).
constexpr int kDependentGateLevels = 8;
constexpr long kSettleEvaluations = 80;
// An unrefined finalist (one that cannot win the final choice on log S + log P) is refined after
// all when its similarity times this reaches kOutclassedRatio times the choice's: the most that
// the rest of its refinement is assumed to raise its full-resolution similarity (measured:
// docs/performance.md "Match", session 13).
constexpr double kUnrefinedGain = 1.5;
// The polish of a finalist whose shader is not deterministic (on a clean pattern) is skipped when
// its similarity times this could not change the final choice. Not a bound: on 149 such polishes
// (43 report photos, 53 synthetic and 18 deterministic targets) it raised the 256 px similarity by
// more for 6, up to 1.91x (the synthetic caustics and bricks targets' own shaders, which the rule
// still polishes: their selection probability lets them win); a replay of the rule on those runs
// skipped 102 of 149 polishes and changed no answer (docs/performance.md "Match", session 14).
constexpr double kPolishGain = 1.1;
// The race on a target that is not a clean pattern (stage 3): lanes race kRaceWave at a time in
// the selection's order until the next lane's best possible score (S = 1) is kUnracedMargin
// below the leader's race score - the leader's 256 px score after its refinement ended up to 0.41
// lower on the report photos and the synthetic targets (coarse vs 256 px similarity). Of the rest,
// a lane races only when its screened similarity times kUnracedReach exceeds kOutclassedRatio
// times the leader's race similarity: a finalist's 256 px similarity was at most 1.3 times its
// screened one for 95 % of the report photos' finalists, and the leader's 256 px similarity at
// least 0.7 times its race similarity for all report photos but one (0.66; 1.3 / 0.7). Heuristics, not bounds:
// what shows them safe is that the answers are the ones of racing every lane (session 16).
constexpr size_t kRaceWave = 2;
constexpr double kUnracedMargin = 0.5;
constexpr double kUnracedReach = 1.85;
constexpr double kPolishStopRmse = 3e-4;  // a polished finalist this exact ends the other polishes  // the settle's renders (default metric, counts pinned)
// The align stage (search/align.h; counts and colours pinned): kAlignEvaluations renders.
constexpr int kAlignMirrorPairDims = 6;  // up to this many dimensions, pairs are mirrored too

// Mean |difference| between renders of one point with two seeds (64 px, linear RGB): 0 for a
// seed-independent point.
double seed_difference(Renderer& renderer, const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed) {
  RenderSettings s;
  s.width = s.height = 64;
  const auto images = renderer.render_batch(decl, {packed, packed}, {seed, seed ^ 0x5bd1e995u}, s);
  double diff = 0;
  for (size_t i = 0; i < images[0].pixels.size(); ++i) diff += std::fabs(images[0].pixels[i] - images[1].pixels[i]);
  return diff / double(images[0].pixels.size());
}

// Below this seed difference a point counts as deterministic (a faint seed-driven grain allowed).
constexpr double kNearlyDeterministic = 0.004;

bool nearly_deterministic(Renderer& renderer, const ShaderDecl& decl, const std::vector<float>& packed, uint32_t seed) {
  return seed_difference(renderer, decl, packed, seed) < kNearlyDeterministic;
}

// Share of the lightness spectrum's energy (DC left out) in its strongest 2% of coefficients:
// near 1 for a clean periodic pattern or a single shape, well below for photographed or noisy
// textures, whose spectra fall off smoothly.
double spectral_peakiness(const metrics::Features& magnitude) {
  const size_t plane = magnitude.values.size() / 3;
  std::vector<double> energy;
  for (size_t i = 1; i < plane; ++i) energy.push_back(std::pow(double(magnitude.values[i]), 4));
  const size_t top = std::max<size_t>(1, energy.size() / 50);
  std::partial_sort(energy.begin(), energy.begin() + top, energy.end(), std::greater<>());
  double strong = 0, total = 0;
  for (size_t i = 0; i < energy.size(); ++i) (i < top ? strong : total) += energy[i];
  total += strong;
  return total > 0 ? strong / total : 0.0;
}

// Share of the lightness spectrum's energy (DC left out; `magnitude` of a MagnitudeMetric at the
// target's full resolution) at frequencies above `cycles` per image.
double energy_share_above(const metrics::Features& magnitude, int size, double cycles) {
  const int half = size / 2 + 1;
  double above = 0, total = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < half; ++x) {
      if (x == 0 && y == 0) continue;
      const double fy = y <= size / 2 ? y : y - size;
      const double e = std::pow(double(magnitude.values[size_t(y) * half + x]), 4);  // |F|^2
      total += e;
      if (std::hypot(double(x), fy) > cycles) above += e;
    }
  return total > 0 ? above / total : 0.0;
}

// A clean pattern with more than kFinePatternShare of its lightness energy above a quarter of
// the refinement resolution (cycles per image: 32 at 128 px, a 4 px period at 256 px) is
// magnitude-polished at the full resolution: at 128 px a 63-stripe target is within a few percent
// of the Nyquist limit and its renders average to nearly flat, so the polish could not see the
// count (deterministic target 7 of the benchmark came back with 57 stripes 22 degrees off). Four
// times the pixels per render, for fine patterns only.
constexpr double kFinePatternShare = 0.5;

int polish_resolution_for(const Image& target, const MatchOptions& o) {
  if (o.resolution <= o.coarse_resolution) return o.coarse_resolution;
  const metrics::MagnitudeMetric full(o.resolution);
  const double share = energy_share_above(full.features(target, o.resolution), o.resolution, o.coarse_resolution / 4.0);
  return share > kFinePatternShare ? o.resolution : o.coarse_resolution;
}

// The other race lanes' end points of a shader, as unit points of the polish's space. A race on
// the statistical metric can end in an alias of the pattern (a clean running-bond target ended as
// an English bond at ratio 3.8) that no local search leaves, while another lane of the same shader
// ended near the truth.
std::vector<std::vector<double>> lane_end_units(const ParameterSpace& space, const ShaderDecl& decl,
                                                const std::vector<std::pair<const ShaderDecl*, std::vector<float>>>& lane_ends,
                                                const std::vector<float>& own, const std::map<std::string, nlohmann::json>& fixed) {
  std::vector<std::vector<double>> units;
  for (const auto& [d, point] : lane_ends)
    if (d == &decl && point != own) {
      std::vector<std::string> pinned;
      units.push_back(space.to_unit(apply_fixed(decl, point, fixed, pinned)));
    }
  return units;
}

// The shader's catalogue samples with the colours of `own` (the magnitude sees colour through the
// CIELAB planes; a sample's random colours would rank it by colour), as unit points of the polish's
// space: starts for the blurred-magnitude stage besides the race's end points. A race on the
// statistical metric can end far from a fine pattern's angle (43 wavy stripes: 12 degrees off,
// where the magnitudes' peaks do not overlap and no local search turns back), while the
// catalogue's samples cover every angle and count; ranking them costs one render each.
std::vector<std::vector<double>> catalogue_units(const ParameterSpace& space, const ShaderDecl& decl,
                                                 const catalog::ShaderCatalogue& catalogue, const std::vector<float>& own,
                                                 const std::map<std::string, nlohmann::json>& fixed) {
  std::vector<std::vector<double>> units;
  for (const auto& sample : catalogue.samples) {
    if (sample.packed.size() != own.size()) continue;
    std::vector<float> packed = sample.packed;
    for (const auto& p : decl.params)
      if (p.type == ParamType::Color) std::copy_n(own.begin() + p.offset, p.width(), packed.begin() + p.offset);
    std::vector<std::string> pinned;
    units.push_back(space.to_unit(apply_fixed(decl, packed, fixed, pinned)));
  }
  return units;
}

// The polish's search: short runs from the shader's refined point and the nearest other lane end
// points (by magnitude); the best gets the rest of the budget.
RefineResult polish_pattern(Objective& objective, const std::vector<double>& own,
                            const std::vector<std::vector<double>>& lane_points, RefineOptions options,
                            nlohmann::json& report) {
  constexpr size_t kLanes = 2;
  std::vector<std::vector<double>> starts = {own};
  if (!lane_points.empty()) {
    const auto similarity = objective.evaluate(lane_points);
    std::vector<size_t> order(lane_points.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return similarity[a] > similarity[b]; });
    for (size_t i = 0; i < std::min(kLanes, order.size()); ++i) starts.push_back(lane_points[order[i]]);
  }
  const long total = options.max_evaluations;
  options.max_evaluations = std::max<long>(1, total / long(2 * starts.size()));
  RefineResult best;
  nlohmann::json tried = nlohmann::json::array();
  for (const auto& start : starts) {
    if (objective.exhausted()) break;
    const auto attempt = refine(objective, start, options);
    tried.push_back(attempt.similarity);
    if (best.unit.empty() || attempt.similarity > best.similarity) best = attempt;
  }
  if (best.unit.empty()) best = {own, objective.evaluate(own), 0, 0};
  options.max_evaluations = std::max<long>(1, total - objective.evaluations());
  if (!objective.exhausted()) {
    const auto more = refine(objective, best.unit, options);
    if (more.similarity >= best.similarity) best = more;
  }
  report["starts"] = tried;
  return best;
}

// A deterministic shader's point after the blurred-magnitude polish gets a line scan of every
// continuous scalar across its whole range (refine.h scan_coordinates) and a short local search
// from what it finds: a wavy stripe pattern's waviness (amplitude, frequency) has sidebands that
// meet the target's only near the true values, so the local searches stop at another waviness.
// `r` is replaced when the scan finds better; `spent`: the match's renders so far (--budget).
// The exact magnitude's polish gets the same scan (it gained more than 0.01 on only 2 of the 18
// deterministic benchmark targets; the soft 8-pointed star came back with 3 points without it)
// and, with `pairs`, the joint sweep of each small count with each scalar (scan_discrete_pairs):
// with the line scan alone that star still came back with 3-4 points in 1 of 4 benchmark runs
// and 2 of 2 CLI runs; with the joint sweep right in all 3 runs since.
nlohmann::json scan_pattern(Objective& objective, RefineResult& r, RefineOptions options, const Budget& budget,
                            long spent, const std::atomic<bool>* stop, bool pairs) {
  long pair_renders = 0;
  const auto& dims = objective.space().dims();
  if (pairs)
    for (const auto& count : dims)
      if (count.levels && count.levels <= kPairMaxLevels)
        for (const auto& d : dims)
          if (!d.levels && d.param->type == ParamType::Float) pair_renders += long(count.levels) * kPairLevels;
  const long dependent_renders = dependent_pair_renders(objective.space(), kDependentGateLevels, kScanLevels);
  // A declared dependency's scan that gains is followed by one more round of both scans: the
  // wave of fine stripes and their angle are confounded (both move the sidebands sideways), so the
  // angle the first line scan chose under a wrong wave may be a few degrees off (63 wavy stripes
  // ended 5 degrees off at another wave in one of two runs; the second round finds both).
  const long line_renders = kScanLevels * long(objective.space().dimensions());
  const long scan_budget = line_renders * kScanRounds + pair_renders + kScanRefineEvaluations +
                           (dependent_renders > 0 ? 2 * dependent_renders + line_renders + 4 : 0);
  if ((stop && *stop) || (budget.max_evaluations > 0 && spent + objective.evaluations() + scan_budget > budget.max_evaluations))
    return nullptr;
  const long evaluations_before = objective.evaluations();
  objective.set_budget({evaluations_before + scan_budget, 0.0});
  auto scanned = scan_coordinates(objective, r.unit, kScanLevels, kScanRounds);
  nlohmann::json report = {{"before", r.similarity}, {"scanned", scanned.similarity}};
  if (dependent_renders > 0) {
    const auto dependent = scan_dependent_pairs(objective, scanned.unit, kDependentGateLevels, kScanLevels);
    report["dependent"] = dependent.similarity;
    if (dependent.similarity > scanned.similarity) {
      scanned = dependent;
      const auto rescanned = scan_coordinates(objective, scanned.unit, kScanLevels, 1);
      const auto again = scan_dependent_pairs(objective, rescanned.unit, kDependentGateLevels, kScanLevels);
      report["rescanned"] = std::max(rescanned.similarity, again.similarity);
      if (again.similarity > scanned.similarity || rescanned.similarity > scanned.similarity)
        scanned = again.similarity >= rescanned.similarity ? again : rescanned;
    }
  }
  if (pair_renders > 0) {
    const auto paired = scan_discrete_pairs(objective, scanned.unit, kPairMaxLevels, kPairLevels);
    report["pairs"] = paired.similarity;
    if (paired.similarity > scanned.similarity) scanned = paired;
  }
  report["evaluations"] = objective.evaluations() - evaluations_before;  // the sweeps'
  if (scanned.similarity > r.similarity) {
    options.max_evaluations = kScanRefineEvaluations;
    const auto further = refine(objective, scanned.unit, options);
    r = further.similarity >= scanned.similarity ? further : scanned;
    report["refined"] = r.similarity;
  }
  return report;
}

}  // namespace

namespace {
// An RMS limit of at most `cap` and at most kPixelExactShare of the target's own RGB deviation.
double limit_for(const Image& target, double cap) {
  const size_t n = static_cast<size_t>(target.width) * target.height;
  if (n == 0) return cap;
  return std::min(cap, kPixelExactShare * flat_rmse(target));
}
}  // namespace

double pixel_exact_limit(const Image& target) { return limit_for(target, kPixelExactRmse); }

double looks_the_same_limit(const Image& target) { return limit_for(target, kLooksTheSameRmse); }

std::string verdict_for(double s, double probability, bool pattern, double pattern_similarity) {
  if ((pattern && s >= kCertainMatch) || (s >= kGoodMatch && probability >= kGoodProbability)) return "good";
  if (s >= kApproximateMatch || pattern_similarity >= kApproximateMatch) return "approximate";
  return "no-match";
}

Image prepare_target(const std::filesystem::path& photo, const std::string& crop_text) {
  Image image = load_image(photo);
  if (!crop_text.empty()) {
    const auto c = parse_crop(crop_text);
    image = crop(image, c[0], c[1], c[2], c[3]);
  }
  if (std::min(image.width, image.height) < 32)
    throw UsageError("target is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                         " pixels; a texture needs at least 32 on each side",
                     "use a larger photo or crop");
  return image;
}

nlohmann::json MatchResult::to_json() const {
  nlohmann::json metrics_json = nlohmann::json::object();
  for (const auto& [k, v] : per_metric) metrics_json[k] = v;
  nlohmann::json cands = nlohmann::json::array();
  for (const auto& c : candidates)
    cands.push_back({{"shader", c.shader}, {"best_pruned", c.best_pruned}, {"best_full", c.best_full},
                     {"screened", c.screened}, {"selection_probability", c.probability}});
  return {{"spec", spec.to_json()}, {"similarity", similarity},     {"metrics", metrics_json},
          {"verdict", verdict},      {"evaluations", evaluations}, {"stopped_early", stopped_early},
          {"candidates", cands},     {"starts", starts},           {"timings", timings},
          {"catalogue", catalogue},
          {"selection_probability", probability},
          {"pattern", pattern},
          {"pattern_similarity", pattern_similarity >= 0 ? nlohmann::json(pattern_similarity) : nlohmann::json(nullptr)},
          {"pixel_exact", pixel_exact},
          {"visibly_other", visibly_other},
          {"outclassed", outclassed},
          {"image_rmse", image_rmse >= 0 ? nlohmann::json(image_rmse) : nlohmann::json(nullptr)},
          {"polish", polish},
          {"selection", {{"version", selection_version()}, {"weight", kSelectionWeight}, {"share", selection_share}}},
          {"thresholds", {{"good", kGoodMatch}, {"good_probability", kGoodProbability}, {"approximate", kApproximateMatch}}}};
}

MatchResult match(const Image& target, catalog::Store& store, const MatchOptions& o,
                  const std::function<void(const MatchProgress&)>& progress, std::atomic<bool>* stop) {
  const auto t_start = Clock::now();
  const metrics::Metric& metric = metrics::default_metric();
  const auto& library = ShaderLibrary::builtin();
  MatchResult result;
  MatchProgress state;
  auto report = [&](const std::string& stage) {
    state.stage = stage;
    state.elapsed = seconds_since(t_start);
    if (progress) progress(state);
  };

  // 1. Target features, once per resolution.
  report("target");
  const auto shaders = usable_shaders(store, o, metric);
  const metrics::Features target_full = metric.features(target, o.resolution);
  const metrics::Features target_coarse = metric.features(target, o.coarse_resolution);
  const SelectionTarget selection(target, metric);
  result.timings["target"] = seconds_since(t_start);

  // 2. Global search. Every sample of every shader is scored by structure (colour left out:
  // the samples' colours are random); shaders are ranked by their best sample, the top-M and
  // those above the threshold stay; the best `screen` samples of each candidate get their colours
  // fitted and are scored with the whole metric at the screening resolution; the best of those
  // become the starting points. The cut by structure matters: screening at 64 px blurs thin
  // structure (mortar joints), and with every shader screened grass outscored bricks there.
  report("global");
  const auto t_global = Clock::now();
  Renderer renderer(library);
  std::vector<ShaderScan> scans;
  for (const auto& s : shaders) {
    ShaderScan scan;
    scan.catalogue = store.load(s.name, false);
    for (const auto& sample : scan.catalogue.samples)
      scan.similarity.push_back(structural_similarity(metric, target_full, sample.features.values));
    for (int i : scan.catalogue.pruned) scan.best_pruned = std::max(scan.best_pruned, scan.similarity[i]);
    scan.best_full = *std::max_element(scan.similarity.begin(), scan.similarity.end());
    scans.push_back(std::move(scan));
  }
  {
    std::vector<std::string> names;
    std::vector<double> nearest;
    for (const auto& scan : scans) {
      names.push_back(scan.catalogue.shader);
      nearest.push_back(scan.best_full);
    }
    const auto p = selection.probabilities(names, nearest);
    for (size_t i = 0; i < scans.size(); ++i) {
      const auto given = o.selection_override.find(names[i]);
      scans[i].probability = o.selection_override.empty() ? p[i]
                             : given != o.selection_override.end() ? given->second : 0.0;
    }
  }
  std::vector<int> order(scans.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  // Ranked by the selection (selection.h): the classifier's probability of the shader's material,
  // ties (shaders the model does not know) by the structurally closest sample of the whole catalogue.
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    if (scans[a].probability != scans[b].probability) return scans[a].probability > scans[b].probability;
    return scans[a].best_full > scans[b].best_full;
  });
  std::vector<int> chosen;
  for (size_t r = 0; r < order.size(); ++r) {
    const bool by_rank = o.candidate_shaders <= 0 || static_cast<int>(r) < o.candidate_shaders || !o.shaders.empty();
    const bool by_threshold = o.shader_threshold > 0 && scans[order[r]].probability >= o.shader_threshold;
    if (by_rank || by_threshold) chosen.push_back(order[r]);
  }
  const ColourTarget colour_target = make_colour_target(target, o.screen_resolution);
  const metrics::Features target_screen = metric.features(colour_target.rgb, o.screen_resolution);
  // The host threads of the screening and the race (the race's comment below).
  const int race_threads = o.budget.max_evaluations > 0 ? 1
                           : o.threads > 0               ? o.threads
                                                         : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  // The candidates are screened independently (each its own renders and colour fits), so on
  // several host threads: one computes features while another's render runs on the device. Each
  // candidate's starts are kept in its slot, so `screened` is in the selection's order whatever
  // the threads.
  std::vector<std::vector<Start>> screened_of(chosen.size());
  std::vector<long> screen_renders(chosen.size(), 0);
  std::mutex screen_mutex;
  size_t screened_so_far = 0;
  parallel_for(chosen.size(), race_threads, [&](size_t k) {
    const auto& scan = scans[chosen[k]];
    const ShaderDecl& decl = library.get(scan.catalogue.shader);
    std::vector<int> best(scan.similarity.size());
    for (size_t i = 0; i < best.size(); ++i) best[i] = static_cast<int>(i);
    const size_t keep = std::min<size_t>(best.size(), std::max(1, o.screen));
    std::partial_sort(best.begin(), best.begin() + keep, best.end(),
                      [&](int a, int b) { return scan.similarity[a] > scan.similarity[b]; });
    std::vector<std::vector<float>> packs;
    std::vector<uint32_t> seeds;
    std::vector<std::string> pinned;
    for (size_t i = 0; i < keep; ++i) {
      const auto& sample = scan.catalogue.samples[best[i]];
      packs.push_back(apply_fixed(decl, sample.packed, o.fixed, pinned));
      seeds.push_back(sample.seed);
    }
    const auto fits = fit_colours(decl, packs, seeds, pinned, colour_target, renderer, false);
    screen_renders[k] = colour_fit_renders(decl, pinned, keep);
    for (size_t i = 0; i < keep; ++i) {
      const double s = metric.similarity(target_screen, metric.features(fits[i].preview, o.screen_resolution));
      screened_of[k].push_back({scan.catalogue.shader, &scan.catalogue.samples[best[i]], s, scan.similarity[best[i]],
                                fits[i].packed, scan.probability});
    }
    // Live previews (proctex serve): the best screened start so far after each candidate - the
    // likeliest materials are screened first - so the first preview does not wait for the whole
    // screening (12 candidates: ~85% of the global search).
    std::lock_guard lock(screen_mutex);
    ++screened_so_far;
    if (progress && screened_so_far < chosen.size()) {
      const Start* top = nullptr;
      for (const auto& starts : screened_of)
        for (const auto& st : starts)
          if (!top || st.similarity > top->similarity) top = &st;
      if (top) {
        state.best_shader = top->shader;
        state.best_spec = spec_from_packed(library.get(top->shader), top->packed, top->sample->seed);
        report("screened " + std::to_string(screened_so_far) + "/" + std::to_string(chosen.size()));
      }
    }
  });
  std::vector<Start> screened;
  long evaluations = 0;
  for (size_t k = 0; k < chosen.size(); ++k) {
    screened.insert(screened.end(), screened_of[k].begin(), screened_of[k].end());
    evaluations += screen_renders[k];
  }
  for (int c : chosen) {
    double screen_best = 0.0;
    for (const auto& st : screened)
      if (st.shader == scans[c].catalogue.shader) screen_best = std::max(screen_best, st.similarity);
    result.candidates.push_back({scans[c].catalogue.shader, scans[c].best_pruned, scans[c].best_full, screen_best,
                                 scans[c].probability});
  }
  // In the selection's order (`chosen` is): the ranking of the shaders by the evidence the
  // refinement cannot game.
  result.timings["global"] = seconds_since(t_global);
  // The best screened start is the first best-so-far spec (live previews); `best` stays for the
  // refinement's similarities, which are at another resolution.
  if (const auto top = std::max_element(screened.begin(), screened.end(),
                                        [](const Start& a, const Start& b) { return a.similarity < b.similarity; });
      top != screened.end()) {
    state.best_shader = top->shader;
    state.best_spec = spec_from_packed(library.get(top->shader), top->packed, top->sample->seed);
    report("screened");
  }

  // 3. Local refinement at the coarse resolution, as a race: the top `race` starts (colours
  // polished first) get a short refinement each, then the best `starts` of them continue with the
  // rest of their evaluations: a short run tells near neighbours apart (bricks from pavers) for a
  // fraction of the renders of refining them all.
  const auto t_local = Clock::now();
  struct Lane {
    Start start;
    const ShaderDecl* decl = nullptr;
    ColourFitResult colours;
    std::unique_ptr<ParameterSpace> space;
    std::unique_ptr<Objective> objective;
    RefineResult refined;
    double race_similarity = 0.0;  // coarse, at the end of the race
    // Prepared (colours fitted, objective made) when first raced; a lane that could not be chosen never is.
    bool raced() const { return objective != nullptr; }
  };
  const int race = std::max(o.starts, o.race);
  std::vector<Lane> lanes;
  std::vector<std::string> by_structure;
  // The structural lanes follow the structural scan (the nearest catalogue samples), not the
  // selection: the race then holds both kinds of evidence.
  std::vector<int> structural_order = chosen;
  std::stable_sort(structural_order.begin(), structural_order.end(),
                   [&](int a, int b) { return scans[a].best_full > scans[b].best_full; });
  for (int c : structural_order) by_structure.push_back(scans[c].catalogue.shader);
  std::vector<std::string> by_selection;
  for (int c : chosen) by_selection.push_back(scans[c].catalogue.shader);
  for (auto& st : choose_race(screened, by_selection, o.selection_lanes, by_structure, race)) {
    Lane lane;
    lane.decl = &library.get(st.shader);
    lane.start = std::move(st);
    lanes.push_back(std::move(lane));
  }
  std::mutex lane_mutex;  // run_lane may run on several threads (the race): guards the shared state
  // A lane's colours are fitted when it is first raced (on the race's threads; a lane that is not
  // raced costs nothing).
  auto prepare_lane = [&](Lane& lane) {
    const Start& st = lane.start;
    std::vector<std::string> pinned;
    apply_fixed(*lane.decl, st.sample->packed, o.fixed, pinned);
    lane.colours = fit_colours(*lane.decl, {st.packed}, {st.sample->seed}, pinned, colour_target, renderer, true).front();
    lane.space = std::make_unique<ParameterSpace>(*lane.decl, lane.colours.packed, pinned);
    lane.objective = std::make_unique<Objective>(*lane.space, target_coarse, metric, renderer, st.sample->seed,
                                                 o.coarse_resolution);
    lane.refined.unit = lane.space->to_unit(lane.colours.packed);
    std::lock_guard lock(lane_mutex);
    evaluations += colour_fit_renders(*lane.decl, pinned, 1);
  };
  // Renders of the lanes still running, so that the reported count only grows while several lanes
  // progress at once (each lane's own count added to the finished lanes' total went back and forth).
  long running_evaluations = 0;
  auto run_lane = [&](Lane& lane, long max_evaluations, const std::string& stage) {
    Objective& objective = *lane.objective;
    const long before = objective.evaluations();
    // What is left of the whole match's budget (0 would mean "unlimited" to the objective, so a
    // spent budget stops it instead).
    Budget budget;
    bool spent = false;
    if (o.budget.max_evaluations > 0) {
      const long left = o.budget.max_evaluations - evaluations;
      spent |= left <= 0;
      budget.max_evaluations = before + std::max<long>(left, 1);
    }
    if (o.budget.max_seconds > 0) {
      const double left = o.budget.max_seconds - seconds_since(t_start);
      spent |= left <= 0;
      budget.max_seconds = std::max(left, 1e-6);
    }
    objective.set_budget(budget);
    if (spent) objective.stop();
    long counted = 0;  // this lane's renders in running_evaluations
    objective.on_progress = [&](const Objective& obj) {
      if (stop && *stop) objective.stop();
      std::lock_guard lock(lane_mutex);
      if (obj.best().similarity > state.best) {
        state.best = obj.best().similarity;
        state.best_shader = lane.start.shader;
        state.best_spec = spec_from_packed(*lane.decl, obj.best().packed, lane.start.sample->seed);
      }
      running_evaluations += obj.evaluations() - before - counted;
      counted = obj.evaluations() - before;
      state.evaluations = evaluations + running_evaluations;
      report(stage);
    };
    if (objective.exhausted() || (stop && *stop)) {
      if (lane.refined.similarity <= 0) lane.refined.similarity = objective.evaluate(lane.refined.unit);  // keeps it in the running
    } else {
      RefineOptions options = o.refine;
      options.max_evaluations = max_evaluations;
      const auto r = refine(objective, lane.refined.unit, options);
      if (r.similarity >= lane.refined.similarity) lane.refined = r;
    }
    std::lock_guard lock(lane_mutex);
    running_evaluations -= counted;
    evaluations += objective.evaluations() - before;
    result.stopped_early |= objective.exhausted() || (stop && *stop);
  };
  const long short_run = std::max<long>(30, o.refine.max_evaluations / 5);
  // The race's lanes are independent (each its own objective, start and seed), so they run on
  // several host threads: one lane computes its features while another's render runs on the
  // device, and the result is the same as one after the other (test Match.ParallelRace*). Not
  // under a render budget (--budget N), which is spent in the lanes' order (race_threads, above).

  // The final choice weighs the similarity with the selection's probability of the shader: a
  // flexible shader that tunes itself into a look-alike must also be a likely material.
  // `share`: the part of selection_weight the selection gets (less on clean patterns, below).
  auto decision = [&](double similarity, double probability, double share = 1.0) {
    return std::log(std::max(similarity, 1e-9)) + share * o.selection_weight * std::log(std::max(probability, 1e-9));
  };
  // Peakiness on the 64 px magnitude (its threshold was set there); the polish compares magnitudes
  // at the refinement's whole resolution, where fine patterns (44 stripes) do not alias.
  static const metrics::MagnitudeMetric peak_magnitude;
  const double peakiness = spectral_peakiness(peak_magnitude.features(target, o.coarse_resolution));
  const bool pattern = peakiness >= kPatternPeakiness;
  auto race_lane = [&](size_t i) {
    prepare_lane(lanes[i]);
    run_lane(lanes[i], short_run, "race " + std::to_string(i + 1) + "/" + std::to_string(lanes.size()));
  };
  if (pattern || o.race_every_lane) {
    parallel_for(lanes.size(), race_threads, race_lane);
  } else {
    // On a photo most lanes cannot be chosen: the final choice maximises log S + lambda log P, and
    // a lane whose lambda log P is below the race leader's score by kUnracedMargin would lose even
    // at S = 1. So the lanes race in the selection's order, kRaceWave at a time (whatever the
    // threads: the same lanes race on any machine), until the next one is such a lane; the leader
    // is then final (no later lane can score above it). Of the lanes left, only those that could
    // still outclass the leader race (their screened similarity times kUnracedReach above
    // kOutclassedRatio times the leader's race similarity). Measured: docs/performance.md
    // "Match", session 16.
    std::vector<size_t> order(lanes.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](size_t a, size_t b) { return lanes[a].start.probability > lanes[b].start.probability; });
    auto race_wave = [&](const std::vector<size_t>& wave) {
      parallel_for(wave.size(), std::min<int>(race_threads, static_cast<int>(wave.size())),
                   [&](size_t k) { race_lane(wave[k]); });
    };
    double leader = -std::numeric_limits<double>::infinity(), leader_similarity = 0.0;
    size_t next = 0;
    while (next < order.size() && (next == 0 || decision(1.0, lanes[order[next]].start.probability) > leader - kUnracedMargin)) {
      const std::vector<size_t> wave(order.begin() + next, order.begin() + std::min(order.size(), next + kRaceWave));
      race_wave(wave);
      for (size_t i : wave) {
        const double d = decision(lanes[i].refined.similarity, lanes[i].start.probability);
        if (d > leader) leader = d, leader_similarity = lanes[i].refined.similarity;
      }
      next += wave.size();
    }
    std::vector<size_t> could_outclass;
    for (; next < order.size(); ++next)
      if (lanes[order[next]].start.similarity * kUnracedReach > kOutclassedRatio * leader_similarity)
        could_outclass.push_back(order[next]);
    for (size_t i = 0; i < could_outclass.size(); i += kRaceWave)
      race_wave(std::vector<size_t>(could_outclass.begin() + i,
                                    could_outclass.begin() + std::min(could_outclass.size(), i + kRaceWave)));
  }
  for (auto& lane : lanes) lane.race_similarity = lane.refined.similarity;
  result.timings["race"] = seconds_since(t_local);  // included in "local"; the rest is the finalists' refinement
  // Finalists: the best `starts` lanes by similarity and selection together, and the best `starts`
  // lanes by the similarity the race reached alone (fewer when they coincide). Either order alone
  // lost a right answer (measured): by the race's similarity the gravel photo's gravel lane lost to
  // grass and cracked_mud look-alikes; weighed with the selection, the 4-pointed star's best lane
  // came third after two circles. The picked lanes lead `lanes`, in similarity order.
  std::stable_sort(lanes.begin(), lanes.end(),
                   [](const Lane& a, const Lane& b) { return a.refined.similarity > b.refined.similarity; });
  size_t finalists = 0;
  {
    const size_t k = std::min<size_t>(lanes.size(), std::max(1, o.starts));
    std::vector<size_t> by_similarity(lanes.size()), by_decision(lanes.size());
    for (size_t i = 0; i < lanes.size(); ++i) by_similarity[i] = by_decision[i] = i;
    std::stable_sort(by_decision.begin(), by_decision.end(), [&](size_t a, size_t b) {
      return decision(lanes[a].refined.similarity, lanes[a].start.probability) >
             decision(lanes[b].refined.similarity, lanes[b].start.probability);
    });
    // On a clean pattern each order keeps only a shader's best lane: the polish runs once per
    // shader from its best finalist, so a second lane of one shader buys nothing there, while it
    // kept out a shader that an exact polish would have made exact (a superellipse target's
    // finalists were three rectangle lanes, noise_stack and sky; superellipse raced fourth by
    // similarity and ended as a rounded rectangle at RMS 0.002).
    const auto first_per_shader = [&](std::vector<size_t>& order) {
      if (!pattern) return;
      std::set<const ShaderDecl*> seen;
      std::vector<size_t> kept;
      for (size_t i : order)
        if (seen.insert(lanes[i].decl).second) kept.push_back(i);
      order = kept;
    };
    first_per_shader(by_similarity);
    first_per_shader(by_decision);
    for (auto* order : {&by_similarity, &by_decision})
      std::erase_if(*order, [&](size_t i) { return !lanes[i].raced(); });
    std::vector<bool> pick(lanes.size(), false);
    for (size_t i = 0; i < std::min(k, by_similarity.size()); ++i) pick[by_similarity[i]] = true;
    for (size_t i = 0; i < std::min(k, by_decision.size()); ++i) pick[by_decision[i]] = true;
    std::vector<Lane> ordered;
    for (int picked = 1; picked >= 0; --picked)
      for (size_t i = 0; i < lanes.size(); ++i)
        if (pick[i] == bool(picked)) ordered.push_back(std::move(lanes[i]));
    lanes = std::move(ordered);
    finalists = static_cast<size_t>(std::count(pick.begin(), pick.end(), true));
  }
  auto refine_finalist = [&](size_t i, size_t done) {
    run_lane(lanes[i], std::max<long>(1, o.refine.max_evaluations - lanes[i].objective->evaluations()),
             "refine " + std::to_string(done) + "/" + std::to_string(finalists));
  };
  // The full-resolution score of a finalist's point: what the final choice compares (stage 4).
  RenderSettings full;
  full.width = full.height = o.resolution;
  const std::vector<double> target_shape = shape_statistics(target, o.resolution);
  struct FullScore {
    double similarity = 0.0;
    metrics::Features features;
    double shape_distance = 0.0;
    Image image;
  };
  auto score_full = [&](size_t i) {
    const Lane& lane = lanes[i];
    FullScore fs;
    fs.image = renderer.render_batch(*lane.decl, {lane.space->to_packed(lane.refined.unit)},
                                     {lane.start.sample->seed}, full).front();
    fs.features = metric.features(fs.image, o.resolution);
    fs.similarity = metric.similarity(target_full, fs.features);
    ++evaluations;
    fs.shape_distance = shape_distance(target_shape, shape_statistics(fs.image, o.resolution));
    return fs;
  };
  std::vector<std::optional<FullScore>> scored(finalists);
  std::vector<bool> unrefined(finalists, false);
  if (pattern || o.refine_every_finalist) {
    // Every finalist is refined here, each its own search (as the race's lanes): on the race's
    // host threads, with the same result as one after the other.
    parallel_for(finalists, race_threads, [&](size_t i) { refine_finalist(i, i + 1); });
  } else {
    // Finalists that cannot win are not refined further (renders are the match's time). The final
    // choice maximises log S + lambda log P with S <= 1, so a finalist whose lambda log P is not
    // above the best score already reached by a refined finalist at the full resolution cannot be
    // chosen by it, however far it were refined: such a finalist keeps its race point (and is still
    // scored, for the outclassed rule below and the JSON). The likeliest finalists go first, so
    // that bound is set early. Not on clean patterns (their polish and certain-match rules decide
    // there), nor for a seed-independent point (its exact polish could make it pixel-exact, which
    // wins outright).
    std::vector<size_t> by_decision(finalists);
    for (size_t i = 0; i < finalists; ++i) by_decision[i] = i;
    std::stable_sort(by_decision.begin(), by_decision.end(), [&](size_t a, size_t b) {
      return decision(lanes[a].refined.similarity, lanes[a].start.probability) >
             decision(lanes[b].refined.similarity, lanes[b].start.probability);
    });
    const auto achieved = [&](size_t i) {
      return decision(scored[i]->similarity, lanes[i].start.probability) - o.shape_weight * scored[i]->shape_distance;
    };
    double best = -std::numeric_limits<double>::infinity();
    const auto ruled_out = [&](size_t i, const std::vector<double>& race_unit) {
      const Lane& lane = lanes[i];
      evaluations += 2;
      return !nearly_deterministic(renderer, *lane.decl, lane.space->to_packed(race_unit), lane.start.sample->seed);
    };
    // In decision order, race_threads finalists at a time (a wave): whether one is refined depends
    // on the scores of those before it (the bound `best`), so the members of a wave that the bound
    // does not rule out yet are refined together, each from a saved state, and then, in order, a
    // member that a member before it has ruled out gets its saved state back - as if it had never
    // been refined. The same result as one after the other (each refinement is its own search); the
    // second core refines while the first does.
    struct Saved {
      RefineResult refined;
      Objective::State objective;
    };
    size_t done = 0;
    for (size_t next = 0; next < by_decision.size();) {
      // A member joins the wave only when the bound it would face, as far as the race's similarities
      // tell (a finalist's 256 px score after refinement was within 0.5 of its race score in log),
      // leaves it refined: on the report photos a second finalist was ruled out in half of the
      // cases, and a refinement undone is a core taken from the one that counts.
      std::vector<size_t> wave;
      double expected_bound = best;
      while (next < by_decision.size() && wave.size() < static_cast<size_t>(race_threads)) {
        const Lane& lane = lanes[by_decision[next]];
        if (!wave.empty() && decision(1.0, lane.start.probability) <= expected_bound) break;
        expected_bound = std::max(expected_bound, decision(lane.refined.similarity, lane.start.probability));
        wave.push_back(by_decision[next++]);
      }
      std::vector<bool> checked(wave.size(), false);
      std::vector<size_t> refined_now;  // wave positions
      std::vector<Saved> saved(wave.size());
      for (size_t k = 0; k < wave.size(); ++k) {
        Lane& lane = lanes[wave[k]];
        if (decision(1.0, lane.start.probability) <= best) {
          checked[k] = true;
          unrefined[wave[k]] = ruled_out(wave[k], lane.refined.unit);
        }
        if (unrefined[wave[k]]) continue;
        if (!checked[k]) saved[k] = {lane.refined, lane.objective->save()};
        refined_now.push_back(k);
      }
      parallel_for(refined_now.size(), std::min<int>(race_threads, static_cast<int>(refined_now.size())),
                   [&](size_t r) { refine_finalist(wave[refined_now[r]], done + refined_now[r] + 1); });
      for (size_t k = 0; k < wave.size(); ++k) {
        const size_t i = wave[k];
        Lane& lane = lanes[i];
        if (!checked[k] && decision(1.0, lane.start.probability) <= best &&
            (unrefined[i] = ruled_out(i, saved[k].refined.unit))) {
          evaluations -= lane.objective->evaluations() - saved[k].objective.evaluations;
          lane.objective->restore(std::move(saved[k].objective));
          lane.refined = std::move(saved[k].refined);
        }
        scored[i] = score_full(i);
        best = std::max(best, achieved(i));
      }
      done += wave.size();
    }
    // The outclassed rule (stage 4) can still choose an unrefined finalist when its similarity is
    // far above the choice's: one within reach of that (refinement raising its similarity by up to
    // kUnrefinedGain) is refined after all, and the choice looked at again.
    for (bool again = true; again;) {
      again = false;
      size_t choice = 0;
      for (size_t i = 1; i < finalists; ++i)
        if (achieved(i) > achieved(choice)) choice = i;
      for (size_t i = 0; i < finalists; ++i)
        if (unrefined[i] &&
            scored[i]->similarity * kUnrefinedGain >= kOutclassedRatio * scored[choice]->similarity) {
          unrefined[i] = false;
          refine_finalist(i, finalists);
          scored[i] = score_full(i);
          again = true;
        }
    }
  }
  struct Refined {
    const ShaderDecl* decl;  // packed: the refined point (replaced by its polish when that is better)
    std::vector<float> packed;
    uint32_t seed;
    double coarse;
    double probability;
  };
  std::vector<Refined> refined;
  for (size_t i = 0; i < lanes.size(); ++i) {
    const auto& lane = lanes[i];
    if (i < finalists)
      refined.push_back({lane.decl, lane.space->to_packed(lane.refined.unit), lane.start.sample->seed,
                         lane.refined.similarity, lane.start.probability});
    result.starts.push_back({{"shader", lane.start.shader},
                             {"catalogue_similarity", lane.start.catalogue_similarity},
                             {"screened_similarity", lane.start.similarity},
                             {"selection_probability", lane.start.probability},
                             {"colours_fitted", lane.colours.fitted},
                             {"colour_similarity", {{"catalogue", lane.colours.before}, {"fitted", lane.colours.after}}},
                             {"refined_similarity_coarse", lane.refined.similarity},
                             {"race_similarity_coarse", lane.race_similarity},
                             {"finalist", i < finalists},
                             {"evaluations", lane.raced() ? lane.objective->evaluations() : 0}});
    if (i < finalists && unrefined[i]) result.starts.back()["refined"] = false;  // cannot win: see above
    if (!lane.raced()) result.starts.back()["raced"] = false;  // could not be chosen: see the race
  }
  result.timings["local"] = seconds_since(t_local);

  // 4. Final scoring at the full resolution: the coarse optimum of each finalist; then, when the
  // target is a clean pattern, an exact polish per finalist shader (5.) whose result competes as
  // one more candidate; the choice weighs similarity with the selection.
  report("final");
  const auto t_final = Clock::now();
  // The magnitude polish of a deterministic shader runs at the refinement's resolution, or at the
  // full one on a fine pattern, whose stripes the coarse renders average away
  // (polish_resolution_for); other shaders' polishes (seed-driven textures: no exact recovery to
  // gain, four times the pixels) stay at the refinement's.
  const int fine_resolution = pattern ? polish_resolution_for(target, o) : o.coarse_resolution;
  struct MagnitudeTarget {
    int resolution;
    metrics::MagnitudeMetric exact, blurred;
    metrics::Features exact_target, blurred_target;
  };
  std::map<int, MagnitudeTarget> magnitude_targets;  // by resolution, made on first use
  const auto magnitude_target = [&](int resolution) -> const MagnitudeTarget& {
    auto it = magnitude_targets.find(resolution);
    if (it == magnitude_targets.end()) {
      const metrics::MagnitudeMetric exact(resolution), blurred(resolution, kPolishBlurBins);
      it = magnitude_targets
               .emplace(resolution, MagnitudeTarget{resolution, exact, blurred, exact.features(target, resolution),
                                                    blurred.features(target, resolution)})
               .first;
    }
    return it->second;
  };
  // What the align stage compares with, built on first use: most targets (photos) never reach it.
  std::optional<AlignStages> stages_aligned;
  std::optional<ColourTarget> registered_target;
  const double exact_limit = pixel_exact_limit(target);
  const double same_limit = looks_the_same_limit(target);
  struct Candidate {
    const Refined* from;
    std::vector<float> packed;
    double similarity;
    metrics::Features features;
    nlohmann::json polish;
    double image_rmse = -1;  // deterministic polish, or a seed-independent point on a clean pattern:
                             // registered RGB RMSE (metrics/aligned.h)
    bool seed_independent = false;  // measured on clean patterns only
    bool deterministic = false;     // nearly (kNearlyDeterministic); finalists on clean patterns only
    double shape_distance = 0;      // to the target (selection.h); 0 for polished points
  };
  // On a clean pattern, a seed-independent finalist's registered RMS: what decides whether its
  // S >= kCertainMatch may still call it "good" (kVisiblyOtherRmse).
  const auto measure_exactness = [&](Candidate& c, const Image& render) {
    if (!pattern) return;
    const double seed_change = seed_difference(renderer, *c.from->decl, c.packed, c.from->seed);
    c.seed_independent = seed_change == 0.0;
    c.deterministic = seed_change < kNearlyDeterministic;
    evaluations += 2;
    if (!c.seed_independent) return;
    if (!registered_target) registered_target = make_colour_target(target, o.resolution);
    c.image_rmse = metrics::AlignedMetric::register_rgb(registered_target->rgb, render).rmse;
  };
  std::vector<Candidate> final_candidates;
  for (size_t i = 0; i < refined.size(); ++i) {
    const auto& rf = refined[i];
    if (!scored[i]) scored[i] = score_full(i);  // scored already when the finalists were (not patterns)
    FullScore& fs = *scored[i];
    const double s = fs.similarity;
    result.starts[i]["refined_similarity"] = s;  // finalists come first in `starts`
    const double shape = fs.shape_distance;
    result.starts[i]["shape_distance"] = shape;
    final_candidates.push_back({&rf, rf.packed, s, std::move(fs.features), nlohmann::json::object()});
    final_candidates.back().shape_distance = shape;
    measure_exactness(final_candidates.back(), fs.image);
    if (final_candidates.back().image_rmse >= 0) result.starts[i]["image_rmse"] = final_candidates.back().image_rmse;
  }

  // The final choice's score of a candidate (used after the polishes, and by the polish's skip rule).
  const auto pixel_exact = [&](const Candidate& c) { return c.image_rmse >= 0 && c.image_rmse <= exact_limit; };
  // A deterministic candidate that registers within the looks-the-same limit of a clean pattern.
  const auto looks_the_same = [&](const Candidate& c) {
    return pattern && c.seed_independent && c.image_rmse >= 0 && c.image_rmse <= same_limit;
  };
  const auto visibly_other = [&](const Candidate& c) {
    return pattern && c.seed_independent && c.image_rmse > kVisiblyOtherRmse;
  };
  // The selection's share of its weight (kPatternSelectionShare), once for the whole choice: reduced
  // on a clean pattern whose most similar finalist is deterministic, before any polish.
  if (pattern && !final_candidates.empty() &&
      std::max_element(final_candidates.begin(), final_candidates.end(), [](const Candidate& a, const Candidate& b) {
        return a.similarity < b.similarity;
      })->deterministic)
    result.selection_share = kPatternSelectionShare;
  const auto score_of = [&](const Candidate& c) {
    return pixel_exact(c) ? 2e6 - c.image_rmse
           : pattern && c.similarity >= kCertainMatch && !visibly_other(c)
               ? 1e6 + c.similarity
           : looks_the_same(c) ? kLooksTheSameScore - c.image_rmse
               : decision(c.similarity, c.from->probability, result.selection_share) -
                     (pattern ? 0.0 : o.shape_weight * c.shape_distance);
  };
  // Whether the polish of a finalist whose shader is not deterministic could change the final
  // choice (clean patterns only; the polish of such a shader is the magnitude polish and a colour
  // fit, never pixel-exact, so its point enters the choice with a similarity S' above the
  // finalist's and the finalist's P, and no shape term). Assuming S' <= kPolishGain x the
  // finalist's S, it cannot: be a certain match (S' >= kCertainMatch), beat the best score of the
  // candidates so far (the final maximum only grows), nor outclass any choice (every candidate
  // that can be outclassed has S >= the least finalist S).
  const auto polish_could_matter = [&](const Candidate& c) {
    const double reach = std::min(1.0, c.similarity * kPolishGain);
    if (reach >= kCertainMatch) return true;
    double best = -std::numeric_limits<double>::infinity(), least = c.similarity;
    for (const auto& other : final_candidates) {
      best = std::max(best, score_of(other));
      least = std::min(least, other.similarity);
    }
    return decision(reach, c.from->probability, result.selection_share) > best || reach > kOutclassedRatio * least;
  };

  // 5. Exact polish of a deterministic pattern (metrics/magnitude.h): the statistical metric
  // cannot tell 7 from 8 brick courses or a bond from its alias well; the whole Fourier
  // magnitude can. Once per shader, from the shader's best finalist.
  const auto t_polish = Clock::now();
  std::vector<std::pair<const ShaderDecl*, std::vector<float>>> lane_ends;  // every race lane's end point
  for (const auto& lane : lanes)
    if (lane.raced()) lane_ends.push_back({lane.decl, lane.space->to_packed(lane.refined.unit)});
  const size_t finalist_count = final_candidates.size();
  std::set<const ShaderDecl*> polished_shaders;
  // Once a polished shader reproduces the target pixel for pixel, the other finalists' polishes
  // (each up to ~2500 renders) cannot beat it: they are skipped. The bar is far below
  // kPixelExactRmse, where a near-equivalent shader (a rounded rectangle for a superellipse, RMS
  // 0.002) must not stop the right one's polish.
  double exact_polish_rmse = -1;
  for (size_t i = 0; i < finalist_count; ++i) {
    const Refined& rf = *final_candidates[i].from;
    if (polished_shaders.count(rf.decl)) continue;
    if (exact_polish_rmse >= 0 && exact_polish_rmse <= kPolishStopRmse) {
      result.starts[i]["polish"] = {{"skipped", "another finalist's polish reproduces the target exactly"}};
      continue;
    }
    size_t best_of_shader = i;
    for (size_t k = 0; k < finalist_count; ++k)
      if (final_candidates[k].from->decl == rf.decl &&
          final_candidates[k].similarity > final_candidates[best_of_shader].similarity)
        best_of_shader = k;
    polished_shaders.insert(rf.decl);
    const Refined& base = *final_candidates[best_of_shader].from;
    nlohmann::json polish = {{"peakiness", peakiness}};
    // Wall seconds per stage (JSON polish.seconds): where a pattern's match spends its time.
    auto lap_start = Clock::now();
    const auto lap = [&](const char* stage) {
      polish["seconds"][stage] = seconds_since(lap_start);
      lap_start = Clock::now();
    };
    // What is left of an evaluation budget (--budget N): the polish never overspends it.
    const long budget_left = o.budget.max_evaluations > 0 ? o.budget.max_evaluations - evaluations : o.polish_evaluations;
    if (o.polish_evaluations <= 0 || budget_left <= 10 || (stop && *stop)) continue;
    std::vector<std::string> pinned;
    const std::vector<float> packed = apply_fixed(*base.decl, base.packed, o.fixed, pinned);
    polish["deterministic"] = nearly_deterministic(renderer, *base.decl, packed, base.seed);
    evaluations += 2;
    if (!polish["deterministic"] && !pattern) {
      final_candidates[best_of_shader].polish = polish;
      continue;
    }
    // Most of a clean-pattern photo's polish time went to shaders that are not deterministic and
    // whose polished point never was the answer (docs/performance.md "Match", session 14).
    if (!polish["deterministic"] && !o.polish_every_finalist && !polish_could_matter(final_candidates[best_of_shader])) {
      polish["skipped"] = "cannot change the final choice";
      final_candidates[best_of_shader].polish = polish;
      result.starts[best_of_shader]["polish"] = polish;
      continue;
    }
    const ParameterSpace space(*base.decl, packed, pinned);
    const MagnitudeTarget& mt = magnitude_target(polish["deterministic"] ? fine_resolution : o.coarse_resolution);
    polish["resolution"] = mt.resolution;
    Objective objective(space, mt.exact_target, mt.exact, renderer, base.seed, mt.resolution);
    const long polish_budget = std::max<long>(1, std::min(budget_left, o.polish_evaluations));
    objective.set_budget({polish_budget, o.budget.max_seconds > 0
                                             ? std::max(o.budget.max_seconds - seconds_since(t_start), 1e-6)
                                             : 0.0});
    objective.on_progress = [&](const Objective& obj) {
      if (stop && *stop) objective.stop();
      state.evaluations = evaluations + obj.evaluations();
      report("polish " + rf.decl->name);
    };
    RefineOptions options = o.refine;
    options.max_evaluations = polish_budget;
    options.sweep_levels = kPolishSweepLevels;
    std::vector<double> own = space.to_unit(packed);
    auto lane_points = lane_end_units(space, *base.decl, lane_ends, base.packed, o.fixed);
    // A deterministic shader first meets the blurred magnitude: its search reaches a stripe count
    // or an angle a few bins off, where the exact magnitude is flat. Its end point then leads the
    // exact polish, which still tries the shader's own point.
    if (polish["deterministic"]) {
      Objective coarse(space, mt.blurred_target, mt.blurred, renderer, base.seed, mt.resolution);
      coarse.set_budget({std::max<long>(1, long(polish_budget * kPolishCoarseShare)), 0.0});
      if (stop && *stop) coarse.stop();
      RefineOptions coarse_options = options;
      coarse_options.max_evaluations = std::max<long>(1, long(polish_budget * kPolishCoarseShare));
      nlohmann::json coarse_report;
      auto coarse_points = lane_points;
      for (const auto& scan : scans)
        if (scan.catalogue.shader == base.decl->name)
          for (auto& u : catalogue_units(space, *base.decl, scan.catalogue, packed, o.fixed)) coarse_points.push_back(std::move(u));
      auto c = polish_pattern(coarse, own, coarse_points, coarse_options, coarse_report);
      const auto coarse_scan = scan_pattern(coarse, c, coarse_options, o.budget, evaluations, stop, false);
      evaluations += coarse.evaluations();
      polish["coarse"] = {{"evaluations", coarse.evaluations()}, {"similarity", c.similarity}, {"scan", coarse_scan}};
      lap("coarse");
      lane_points.insert(lane_points.begin(), own);
      own = c.unit;
    }
    auto r = polish_pattern(objective, own, lane_points, options, polish);
    if (polish["deterministic"]) polish["scan"] = scan_pattern(objective, r, options, o.budget, evaluations, stop, true);
    evaluations += objective.evaluations();
    lap("exact");
    // The magnitude weighs colour through the CIELAB planes' spectra only; the closed-form
    // colour fit (colour_fit.h) then sets the free colours from the target's colour statistics.
    const std::vector<float> polished = space.to_packed(r.unit);
    const auto recoloured = fit_colours(*base.decl, {polished}, {base.seed}, pinned, colour_target, renderer, true).front();
    evaluations += colour_fit_renders(*base.decl, pinned, 1);
    polish["evaluations"] = objective.evaluations();
    std::vector<std::vector<float>> tries = {polished};
    std::vector<std::string> names = {"similarity"};
    if (recoloured.fitted) {
      tries.push_back(recoloured.packed);
      names.push_back("recoloured_similarity");
    }
    // Settle: the magnitude is blind to what the default metric also weighs (a softness, a vein's
    // width), so a polished point with exact counts could lose the final choice to a finalist with
    // wrong ones. A short refinement on the default metric with the discrete parameters pinned lets
    // it compete on equal terms (8- vs 3-pointed soft star: measured, docs/match-evaluation.md).
    if (polish["deterministic"] && !(stop && *stop)) {
      std::vector<std::string> settle_pinned = pinned;
      for (const auto& d : space.dims())
        if (d.levels) settle_pinned.push_back(d.param->name);
      const ParameterSpace settle_space(*base.decl, tries.back(), settle_pinned);
      if (settle_space.dimensions() > 0) {
        Objective settle(settle_space, target_coarse, metric, renderer, base.seed, o.coarse_resolution);
        settle.set_budget({kSettleEvaluations, 0.0});
        RefineOptions settle_options = o.refine;
        settle_options.max_evaluations = kSettleEvaluations;
        const auto settled = refine(settle, settle_space.to_unit(tries.back()), settle_options);
        evaluations += settle.evaluations();
        tries.push_back(settle_space.to_packed(settled.unit));
        names.push_back("settled_similarity");
      }
      // Align: with the counts right, what is still off is continuous (a duty, a softness, an
      // amplitude), which the statistics and the magnitude see weakly and pixels see directly.
      // The registered-pixel metric ignores where the pattern starts and its colours (refitted
      // after), so this short search moves the shape only.
      std::vector<std::string> align_pinned = settle_pinned;
      for (const auto& p : base.decl->params)
        if (p.type == ParamType::Color) align_pinned.push_back(p.name);
      // The counts the stage keeps: the settled point's, and - when the magnitude polish changed
      // them - also the refined finalist's, each given the whole stage; the better registered end
      // point is kept (a 2-arm swirl's polish moved to 3 arms, registered S 0.001, RMS 0.06).
      const auto counts_differ = [&](const std::vector<float>& a, const std::vector<float>& b) {
        const auto ua = space.to_unit(a), ub = space.to_unit(b);
        for (size_t d = 0; d < ua.size(); ++d)
          if (space.dims()[d].levels && std::fabs(ua[d] - ub[d]) > 1e-9) return true;
        return false;
      };
      std::vector<std::vector<float>> align_bases = {tries.back()};
      if (counts_differ(packed, tries.back())) align_bases.push_back(packed);
      // Within --budget only (renders or seconds): the stage is all or nothing.
      const bool align_fits =
          (o.budget.max_evaluations <= 0 ||
           evaluations + kAlignEvaluations * long(align_bases.size()) <= o.budget.max_evaluations) &&
          (o.budget.max_seconds <= 0 || seconds_since(t_start) < o.budget.max_seconds) && !(stop && *stop);
      std::optional<ParameterSpace> align_space;
      RefineResult r_align;
      long align_evaluations = 0;
      nlohmann::json align_runs = nlohmann::json::array();
      for (const auto& align_base : align_bases) {
        ParameterSpace candidate_space(*base.decl, align_base, align_pinned);
        if (candidate_space.dimensions() == 0 || !align_fits) break;
        if (!stages_aligned) {
          stages_aligned = align_stages(target, o.resolution);
          registered_target = make_colour_target(target, o.resolution);
        }
        // Starts: the base point, the polished one, and the base mirrored (u -> 1 - u) in each
        // dimension and each pair of dimensions: the statistics cannot tell a swirl's twist from
        // its mirror, nor a duty from its complement in swapped colours (which turns the arms), and
        // a local search does not cross over.
        std::vector<std::vector<double>> align_starts = {candidate_space.to_unit(align_base),
                                                         candidate_space.to_unit(tries.front())};
        const int dims = candidate_space.dimensions();
        for (int d = 0; d < dims; ++d)
          for (int e = d; e < (dims <= kAlignMirrorPairDims ? dims : d + 1); ++e) {
            auto mirrored = align_starts.front();
            mirrored[d] = 1.0 - mirrored[d];
            if (e != d) mirrored[e] = 1.0 - mirrored[e];
            align_starts.push_back(mirrored);
          }
        // The rescue (align.h) when the stages miss the target: within --budget only.
        const bool rescue_fits =
            (o.budget.max_evaluations <= 0 ||
             evaluations + align_evaluations + kAlignEvaluations * long(align_bases.size()) +
                     align_rescue_renders(candidate_space) <= o.budget.max_evaluations) &&
            (o.budget.max_seconds <= 0 || seconds_since(t_start) < o.budget.max_seconds) && !(stop && *stop);
        nlohmann::json rescue_report;
        const auto run = align_pattern(candidate_space, align_starts, *stages_aligned, renderer, base.seed,
                                       o.resolution, o.refine, align_evaluations, rescue_fits, &rescue_report);
        if (!rescue_report.is_null()) polish["align_rescue"].push_back(rescue_report);  // per align base
        align_runs.push_back(run.similarity);
        if (!align_space || run.similarity > r_align.similarity) {
          align_space.emplace(std::move(candidate_space));
          r_align = run;
        }
      }
      if (align_space) {
        evaluations += align_evaluations;
        if (align_runs.size() > 1) polish["align_counts"] = align_runs;  // settled's, finalist's
        const std::vector<float> shaped = align_space->to_packed(r_align.unit);
        // Colours: the shape is now registered with the target, so its pixels give them (least
        // squares at the refinement's resolution); the histogram fit competes in the final choice.
        const auto coloured = fit_colours(*base.decl, {shaped}, {base.seed}, pinned, colour_target, renderer, true).front();
        const auto registered =
            fit_colours(*base.decl, {shaped}, {base.seed}, pinned, *registered_target, renderer, false, true).front();
        evaluations += 2 * colour_fit_renders(*base.decl, pinned, 1);
        tries.push_back(registered.packed);
        names.push_back("registered_similarity");
        polish["aligned"] = {{"evaluations", align_evaluations},
                             {"similarity", r_align.similarity},
                             {"params", spec_from_packed(*base.decl, coloured.packed, base.seed).params}};
        tries.push_back(coloured.packed);
        names.push_back("aligned_similarity");
      }
    }
    lap("settle_align");
    auto images = renderer.render_batch(*base.decl, tries, std::vector<uint32_t>(tries.size(), base.seed), full);
    evaluations += static_cast<long>(tries.size());
    // 6. Pixel polish (pixel_polish.h): from the try that registers best, the plain RGB
    // difference decides what the statistics and the registered pixels cannot (a softness traded
    // against a duty and a colour; swapped colours hidden by a shift).
    if (polish["deterministic"] && !(stop && *stop)) {
      if (!registered_target) registered_target = make_colour_target(target, o.resolution);
      size_t closest = 0;
      double closest_rmse = -1;
      for (size_t k = 0; k < tries.size(); ++k) {
        const double rmse = metrics::AlignedMetric::register_rgb(registered_target->rgb, images[k]).rmse;
        if (closest_rmse < 0 || rmse < closest_rmse) {
          closest_rmse = rmse;
          closest = k;
        }
      }
      const long pixel_budget = o.budget.max_evaluations > 0
                                    ? std::min(kPixelPolishBudget, o.budget.max_evaluations - evaluations)
                                    : kPixelPolishBudget;
      // The polish itself decides which starts are close enough (pixel_polish.h): at the
      // shader's origin, after a colour fit, up to kPixelPolishOriginStartRmse - a soft ring
      // registered at RMS 0.067 in the wrong colours polished to 2e-7 (session 21).
      if (closest_rmse <= kPixelPolishOriginStartRmse && pixel_budget > 10) {
        nlohmann::json pixel_report;
        const auto px = pixel_polish(*base.decl, tries[closest], base.seed, pinned, registered_target->rgb, renderer,
                                     pixel_budget, pixel_report);
        evaluations += px.evaluations;
        polish["pixel"] = nlohmann::json{{"from", names[closest]}, {"starts", pixel_report}, {"evaluations", px.evaluations}};
        if (px.rmse >= 0) {
          tries.push_back(px.packed);
          names.push_back("pixel_polished_similarity");
          images.push_back(renderer.render_batch(*base.decl, {px.packed}, std::vector<uint32_t>{base.seed}, full).front());
          evaluations += 1;
          polish["pixel"]["start"] = px.start;
          polish["pixel"]["rmse"] = px.rmse;
          polish["pixel"]["shift"] = nlohmann::json::array({px.dx, px.dy});
        }
      }
    }
    lap("pixel");
    double best_s = final_candidates[best_of_shader].similarity;
    int kept = -1;
    std::vector<metrics::Features> features;
    for (size_t k = 0; k < tries.size(); ++k) {
      features.push_back(metric.features(images[k], o.resolution));
      const double sp = metric.similarity(target_full, features.back());
      polish[names[k]] = sp;
      if (sp > best_s) {
        best_s = sp;
        kept = static_cast<int>(k);
      }
    }
    // Pixels over statistics: a point that reproduces the target pixel for pixel (up to where the
    // pattern starts) is the answer whatever the default similarity says of it - that metric rated
    // a chevron 0.60 at an RGB RMSE of 0.005, invisible to anyone.
    double kept_rmse = -1;
    if (polish["deterministic"]) {
      if (!registered_target) registered_target = make_colour_target(target, o.resolution);
      nlohmann::json rmses = nlohmann::json::object();
      std::vector<double> rmse_of(tries.size());
      int exact = -1;
      double exact_rmse = exact_limit;
      for (size_t k = 0; k < tries.size(); ++k) {
        const double rmse = metrics::AlignedMetric::register_rgb(registered_target->rgb, images[k]).rmse;
        rmses[names[k]] = rmse;
        rmse_of[k] = rmse;
        if (rmse <= exact_rmse) {
          exact_rmse = rmse;
          exact = static_cast<int>(k);
        }
        if (static_cast<int>(k) == kept) kept_rmse = rmse;
      }
      polish["image_rmse"] = rmses;
      if (exact >= 0) {
        kept = exact;
        kept_rmse = exact_rmse;
        best_s = metric.similarity(target_full, features[exact]);
      } else {
        // Not pixel-exact, but close to the eye where what the statistics prefer is visibly
        // another image (looks_the_same, match.h): the pixels decide. A ring target's pixel polish
        // reached RMS 0.009 while the similarity kept its finalist - the colours swapped, the
        // ring inverted, RMS 0.12 - since it rated that 0.65 and the near-copy 0.50 (session 19).
        const int nearest = rmse_of.empty() ? -1
                            : static_cast<int>(std::min_element(rmse_of.begin(), rmse_of.end()) - rmse_of.begin());
        const double preferred_rmse = kept >= 0 ? rmse_of[kept] : final_candidates[best_of_shader].image_rmse;
        const double nearest_rmse = nearest >= 0 ? rmse_of[nearest] : -1.0;
        if (nearest >= 0 && nearest != kept && nearest_rmse <= same_limit &&
            (preferred_rmse < 0 || preferred_rmse > kVisiblyOtherRmse)) {
          kept = nearest;
          kept_rmse = nearest_rmse;
          best_s = metric.similarity(target_full, features[nearest]);
          polish["looks_the_same"] = true;
        }
      }
    }
    polish["kept"] = kept >= 0;
    if (kept >= 0) polish["kept_point"] = names[kept];
    // Kept only if the default similarity agrees that it is better than the shader's finalists,
    // or if it is pixel-exact.
    if (kept >= 0 && kept_rmse >= 0 && (exact_polish_rmse < 0 || kept_rmse < exact_polish_rmse))
      exact_polish_rmse = kept_rmse;
    if (kept >= 0) {
      final_candidates.push_back({&base, tries[kept], best_s, std::move(features[kept]), polish, kept_rmse});
      if (pattern)
        final_candidates.back().seed_independent =
            seed_difference(renderer, *base.decl, tries[kept], base.seed) == 0.0;
    } else
      final_candidates[best_of_shader].polish = polish;
    result.starts[best_of_shader]["polish"] = polish;
    if (kept >= 0) result.starts[best_of_shader]["polished_similarity"] = best_s;
  }
  const double polish_seconds = seconds_since(t_polish);

  // A near-certain similarity wins outright (the verdict's kCertainMatch); otherwise similarity
  // and selection decide together.
  // When the choice reproduces the target at less than 1/kOutclassedRatio of another finalist's
  // similarity, that finalist is chosen instead, however likely the selection finds the first
  // one's material: the selection can be sure and wrong (a knit render: P(grass) 0.96, grass S 0.135
  // against knit's 0.599).
  const Candidate* final_choice = nullptr;
  const Candidate* most_similar = nullptr;
  for (const auto& c : final_candidates) {
    if (!final_choice || score_of(c) > score_of(*final_choice)) final_choice = &c;
    if (!most_similar || c.similarity > most_similar->similarity) most_similar = &c;
  }
  const bool outclassed = final_choice && score_of(*final_choice) < kLooksTheSameScore - 1.0 && final_choice->similarity * kOutclassedRatio < most_similar->similarity;
  if (outclassed) final_choice = most_similar;
  if (final_choice) {
    const Candidate& c = *final_choice;
    result.probability = c.from->probability;
    // One value of each symmetry class (shader.h `period=`: a star turned by 360/n is the same
    // image), so that equal images give equal answers.
    result.spec = spec_from_packed(*c.from->decl, canonical_packed(*c.from->decl, c.packed), c.from->seed);
    result.similarity = c.similarity;
    result.polish = c.polish;
    result.image_rmse = c.image_rmse;
    result.pixel_exact = pixel_exact(c);
    result.visibly_other = visibly_other(c);
    result.outclassed = outclassed;
    result.per_metric.clear();
    const auto* composite = dynamic_cast<const metrics::CompositeMetric*>(&metric);
    if (composite)
      for (const auto& [name, value] : composite->breakdown(target_full.values, c.features.values)) result.per_metric[name] = value;
    result.per_metric[metric.id()] = c.similarity;
    if (composite && pattern)
      result.pattern_similarity = composite->similarity_without(target_full.values, c.features.values, "spectrum");
  }
  result.timings["polish"] = polish_seconds;  // included in "final"
  result.timings["final"] = seconds_since(t_final);
  result.evaluations = evaluations;
  result.pattern = pattern;
  // A seed-independent result that registers visibly off the target is not an exact recovery,
  // whatever its similarity: the clean-pattern rule (S >= kCertainMatch) does not make it good.
  result.verdict = result.pixel_exact ? "good"
                                      : verdict_for(result.similarity, result.probability,
                                                    result.pattern && !result.visibly_other, result.pattern_similarity);
  result.timings["total"] = seconds_since(t_start);
  result.timings["compile"] = ocl::Runtime::instance().build_seconds();  // included in the stages above
  nlohmann::json names = nlohmann::json::array();
  for (const auto& s : shaders) names.push_back(s.name);
  result.catalogue = {{"path", store.path().string()}, {"shaders", names}, {"metric", metric.id()},
                      {"metric_version", metric.version()}, {"resolution", o.resolution}};
  return result;
}

}  // namespace proctex::search
