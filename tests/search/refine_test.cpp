// Local refinement recovers the parameters of deterministic targets, whole values included.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "metrics/magnitude.h"
#include "search/refine.h"
#include "shaders/library.h"
#include "shaders/spec.h"

namespace proctex::search {
namespace {

constexpr int kResolution = 128;

struct Fixture {
  const ShaderDecl& decl;
  ParameterSpace space;
  Renderer renderer;
  metrics::Features target;

  std::string spec;

  Fixture(const std::string& target_spec)
      : decl(ShaderLibrary::builtin().get(parse_spec_argument(target_spec).shader)), space(decl), spec(target_spec) {
    target = target_for(metrics::default_metric());
  }
  // The target's features under another metric (a Fourier magnitude, as the pattern polish uses).
  metrics::Features target_for(const metrics::Metric& metric) {
    RenderSettings s;
    s.width = s.height = kResolution;
    return metric.features(renderer.render(parse_spec_argument(spec), s), kResolution);
  }
};

TEST(Refine, RecoversCheckerCountAndColourFromANearbyStart) {
  Fixture f("checker:squares=6,color_a=(0.7,0.2,0.1)");
  Objective objective(f.space, f.target, metrics::default_metric(), f.renderer, 0, kResolution);
  const auto start = f.space.to_unit(resolve(f.decl, parse_spec_argument("checker:squares=4")));
  const RefineResult r = refine(objective, start, {});
  const auto packed = f.space.to_packed(r.unit);
  EXPECT_EQ(packed[f.decl.find("squares")->offset], 6.0f);
  // The two colours are interchangeable (a checker shifted by one square), so compare the pair.
  const float a = packed[f.decl.find("color_a")->offset], b = packed[f.decl.find("color_b")->offset];
  EXPECT_NEAR(std::max(a, b), 0.7f, 0.15f);
  EXPECT_GT(r.similarity, 0.75);
  EXPECT_LE(r.evaluations, RefineOptions{}.max_evaluations + 64);  // polish adds a few
}

TEST(Refine, NeverEvaluatesNonIntegerCounts) {
  Fixture f("checker:squares=9");
  Objective objective(f.space, f.target, metrics::default_metric(), f.renderer, 0, kResolution);
  objective.on_progress = [&](const Objective& o) {
    const float squares = o.best().packed[f.decl.find("squares")->offset];
    ASSERT_EQ(squares, std::round(squares));
  };
  refine(objective, std::vector<double>(f.space.dimensions(), 0.5), {});
}

TEST(Refine, BudgetStopsTheSearchWithTheBestSoFar) {
  Fixture f("checker:squares=7");
  Objective objective(f.space, f.target, metrics::default_metric(), f.renderer, 0, kResolution);
  objective.set_budget({.max_evaluations = 10});
  const RefineResult r = refine(objective, std::vector<double>(f.space.dimensions(), 0.2), {});
  EXPECT_LE(objective.evaluations(), 12);
  EXPECT_GT(r.similarity, 0.0);
  EXPECT_EQ(r.similarity, objective.best().similarity);
}

// A speculative refinement that is not wanted (the match's finalists, refined two at a time) is
// undone: after restore the objective answers, counts and keeps its best as if it had never run.
TEST(Objective, RestoreUndoesASearchAsIfItHadNotRun) {
  Fixture f("checker:squares=6");
  Objective objective(f.space, f.target, metrics::default_metric(), f.renderer, 0, kResolution);
  const std::vector<double> start(f.space.dimensions(), 0.3);
  const double at_start = objective.evaluate(start);
  const Objective::State saved = objective.save();
  RefineOptions options;
  options.max_evaluations = 60;
  const RefineResult r = refine(objective, start, options);
  ASSERT_GT(objective.evaluations(), 1);
  ASSERT_GT(r.similarity, at_start) << "the search found nothing to undo";
  const std::vector<float> found = f.space.to_packed(r.unit);
  objective.restore(saved);
  EXPECT_EQ(objective.evaluations(), 1);
  EXPECT_EQ(objective.best().similarity, at_start);
  EXPECT_EQ(objective.best().packed, f.space.to_packed(start));
  EXPECT_EQ(objective.evaluate(start), at_start);
  EXPECT_EQ(objective.evaluations(), 1) << "the start is still answered from the cache";
  EXPECT_EQ(objective.evaluate(r.unit), r.similarity) << "the undone point is rendered again, same value";
  EXPECT_EQ(objective.evaluations(), 2) << "the undone search's cache entries are gone";
  EXPECT_EQ(f.space.to_packed(r.unit), found);
}

TEST(Refine, EveryOptimizerImprovesOnItsStart) {
  for (const auto& name : optimizer_names()) {
    Fixture f("checker:squares=5,color_b=(0.3,0.3,0.6)");
    Objective objective(f.space, f.target, metrics::default_metric(), f.renderer, 0, kResolution);
    const std::vector<double> start(f.space.dimensions(), 0.3);
    const double at_start = objective.evaluate(start);
    RefineOptions options;
    options.optimizer = parse_optimizer(name);
    options.max_evaluations = 120;
    const RefineResult r = refine(objective, start, options);
    EXPECT_GT(r.similarity, 5 * at_start) << name;
    EXPECT_LE(r.evaluations, options.max_evaluations + 64) << name;
  }
  EXPECT_THROW(parse_optimizer("simulated-annealing"), UsageError);
}

}  // namespace
}  // namespace proctex::search

namespace proctex::search {

// Stripes with only `wave` and `wave_frequency` searched: the truth's other parameters pinned, the
// search starting from the truth with the wave and frequency given.
struct WaveSearch {
  Fixture f;
  ParameterSpace space;
  std::vector<float> start;
  WaveSearch(const std::string& truth, float wave, float frequency)
      : f(truth), space(f.decl, start_of(f, truth, wave, frequency), others(f)),
        start(start_of(f, truth, wave, frequency)) {}
  static std::vector<float> start_of(const Fixture& f, const std::string& truth, float wave, float frequency) {
    auto s = resolve(f.decl, parse_spec_argument(truth));
    s[f.decl.find("wave")->offset] = wave;
    s[f.decl.find("wave_frequency")->offset] = frequency;
    return s;
  }
  static std::vector<std::string> others(const Fixture& f) {
    std::vector<std::string> pinned;
    for (const auto& p : f.decl.params)
      if (p.name != "wave" && p.name != "wave_frequency") pinned.push_back(p.name);
    return pinned;
  }
  float value(const RefineResult& r, const std::string& name) const {
    return space.to_packed(r.unit)[f.decl.find(name)->offset];
  }
};

TEST(ScanCoordinates, FindsAStripePatternsWavinessWhereTheLocalSearchStops) {
  // Wavy stripes (a deterministic benchmark target): the waviness shows in the Fourier magnitude
  // (blurred, as the coarse polish compares it) as sidebands that meet the target's only near the
  // true wave frequency, so a local search from strongly waved stripes at the wrong frequency
  // stays there. A line scan across each parameter's whole range finds the sidebands.
  WaveSearch w("stripes:stripes=52,angle=52,duty=0.26,softness=0.88,wave=0.3,wave_frequency=2.76", 0.9f, 1.0f);
  Fixture& f = w.f;
  const ParameterSpace& space = w.space;
  const auto& start = w.start;
  const auto value = [&](const RefineResult& r, const std::string& name) { return w.value(r, name); };
  const metrics::MagnitudeMetric magnitude(kResolution, 2.0);  // blurred by 2 bins, as match.cpp's coarse polish
  const auto target = f.target_for(magnitude);
  ASSERT_EQ(space.dimensions(), 2);

  Objective local(space, target, magnitude, f.renderer, 0, kResolution);
  const RefineResult stuck = refine(local, space.to_unit(start), {});
  EXPECT_GT(std::fabs(value(stuck, "wave_frequency") - 2.76f), 0.3f) << "the local search alone found it";

  Objective scanned_objective(space, target, magnitude, f.renderer, 0, kResolution);
  const RefineResult scanned = scan_coordinates(scanned_objective, space.to_unit(start), 48, 2);
  EXPECT_NEAR(value(scanned, "wave_frequency"), 2.76f, 0.5f);  // within the sidebands' reach
  EXPECT_GT(scanned.similarity, stuck.similarity);
  // From there the local search on the exact magnitude (match.cpp's next stage) reaches the truth.
  const metrics::MagnitudeMetric exact(kResolution);
  const auto exact_target = f.target_for(exact);
  Objective exact_objective(space, exact_target, exact, f.renderer, 0, kResolution);
  const RefineResult refined = refine(exact_objective, scanned.unit, {});
  EXPECT_NEAR(value(refined, "wave_frequency"), 2.76f, 0.1f);
  EXPECT_NEAR(value(refined, "wave"), 0.3f, 0.03f);
  EXPECT_LE(scanned.evaluations, 1 + 2 * 2 * 48);
}

}  // namespace proctex::search

namespace proctex::search {

TEST(ScanDiscretePairs, FindsASoftStarsCountWhereNeitherSweepAloneDoes) {
  // A soft 8-pointed star with inner radius 0.87 is nearly a disc; a 4-pointed look-alike at inner
  // radius 0.95 renders within RMS 0.004 of it (a deterministic benchmark target that came back
  // that way). There, every count looks alike, so a sweep of the count alone stays; swept jointly
  // with the radius, the count comes back.
  const std::string truth = "star:points=8,inner=0.871,size=0.583,softness=0.412,rotation=45";
  Fixture f(truth);
  const metrics::MagnitudeMetric magnitude(kResolution);
  const auto target = f.target_for(magnitude);
  auto start = resolve(f.decl, parse_spec_argument(truth));
  start[f.decl.find("points")->offset] = 4.0f;
  start[f.decl.find("inner")->offset] = 0.95f;
  std::vector<std::string> pinned;
  for (const auto& p : f.decl.params)
    if (p.type == ParamType::Color) pinned.push_back(p.name);
  const ParameterSpace space(f.decl, start, pinned);
  const auto value = [&](const std::vector<double>& unit, const std::string& name) {
    return space.to_packed(unit)[f.decl.find(name)->offset];
  };

  RefineResult alone{space.to_unit(start), 0.0, 0, 0};
  {
    Objective objective(space, target, magnitude, f.renderer, 0, kResolution);
    RefineOptions options;
    options.max_evaluations = 0;  // the discrete sweep only
    options.probe_bounds = false;
    alone = refine(objective, space.to_unit(start), options);
  }
  EXPECT_NE(value(alone.unit, "points"), 8.0f) << "a sweep of the count alone found it";

  Objective objective(space, target, magnitude, f.renderer, 0, kResolution);
  const RefineResult paired = scan_discrete_pairs(objective, space.to_unit(start), 16, 16);
  EXPECT_EQ(value(paired.unit, "points"), 8.0f);
  EXPECT_NEAR(value(paired.unit, "inner"), 0.871f, 0.06f);
  EXPECT_GT(paired.similarity, alone.similarity);
}

// Fine wavy stripes (43 across, a wave of 0.30 period at 2.73 waves; session 21's fresh benchmark
// target 25, which ended straight): the stripes declare `wave_frequency ... needs=wave`. From
// straight stripes the line scan misses the frequency - it does nothing while the wave is off, and
// the wave scanned at the start's frequency ends at another waviness (0.57 waves at 1) - while the
// joint scan of the declared pair lands in the truth's basin, from which the exact magnitude's
// local search reaches it.
TEST(ScanDependentPairs, FindsTheWaveOfStraightStripesWhereTheLineScanCannot) {
  WaveSearch w("stripes:stripes=43,angle=81.1469,duty=0.42196,softness=0.20113,wave=0.30271,wave_frequency=2.73295",
               0.0f, 1.0f);
  Fixture& f = w.f;
  const ParameterSpace& space = w.space;
  const auto& start = w.start;
  const auto value = [&](const RefineResult& r, const std::string& name) { return w.value(r, name); };
  const metrics::MagnitudeMetric magnitude(kResolution, 2.0);  // blurred by 2 bins, as match.cpp's coarse polish
  const auto target = f.target_for(magnitude);
  ASSERT_EQ(space.dimensions(), 2);
  EXPECT_EQ(dependent_pair_renders(space, 8, 48), 8 * 48);

  Objective line(space, target, magnitude, f.renderer, 0, kResolution);
  const RefineResult lined = scan_coordinates(line, space.to_unit(start), 48, 2);
  EXPECT_GT(std::fabs(value(lined, "wave_frequency") - 2.73f), 0.5f)
      << "the line scan found the frequency; wave " << value(lined, "wave");

  Objective joint(space, target, magnitude, f.renderer, 0, kResolution);
  const RefineResult scanned = scan_dependent_pairs(joint, space.to_unit(start), 8, 48);
  EXPECT_NEAR(value(scanned, "wave_frequency"), 2.73f, 0.3f);
  EXPECT_GT(scanned.similarity, lined.similarity);
  EXPECT_LE(scanned.evaluations, 1 + 8 * 48);
  const metrics::MagnitudeMetric exact(kResolution);
  const auto exact_target = f.target_for(exact);
  Objective exact_objective(space, exact_target, exact, f.renderer, 0, kResolution);
  const RefineResult refined = refine(exact_objective, scanned.unit, {});
  EXPECT_NEAR(value(refined, "wave_frequency"), 2.733f, 0.02f * 11);
  EXPECT_NEAR(value(refined, "wave"), 0.303f, 0.02f);
}

// Nothing declared, nothing spent: a shader without `needs=` gets no joint scan.
TEST(ScanDependentPairs, CostsNothingWithoutADeclaration) {
  Fixture f("checker:squares=5");
  EXPECT_EQ(dependent_pair_renders(f.space, 8, 48), 0);
  Objective objective(f.space, f.target, metrics::default_metric(), f.renderer, 0, kResolution);
  const std::vector<double> start(f.space.dimensions(), 0.3);
  const RefineResult r = scan_dependent_pairs(objective, start, 8, 48);
  EXPECT_EQ(r.evaluations, 1);
}

}  // namespace proctex::search
