// Local refinement recovers the parameters of deterministic targets, whole values included.
#include <gtest/gtest.h>

#include "core/error.h"
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

  Fixture(const std::string& target_spec)
      : decl(ShaderLibrary::builtin().get(parse_spec_argument(target_spec).shader)), space(decl) {
    RenderSettings s;
    s.width = s.height = kResolution;
    target = metrics::default_metric().features(renderer.render(parse_spec_argument(target_spec), s), kResolution);
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
