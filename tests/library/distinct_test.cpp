// The library spans distinct looks: no two shaders are near-duplicates at their defaults under the
// default metric (a near-duplicate wastes catalogue space and confuses matching).
#include <gtest/gtest.h>

#include "metrics/metric.h"
#include "shaders/library.h"
#include "shaders/renderer.h"

namespace proctex {
namespace {

// Two crops of one photographed texture score about 0.6-0.75 under the default metric
// (docs/metrics.md); two shaders' defaults scoring above that are as alike as one texture.
constexpr double kNearDuplicate = 0.6;

TEST(Library, NoTwoShadersAreNearDuplicatesAtTheirDefaults) {
  const auto& lib = ShaderLibrary::builtin();
  const auto& metric = metrics::default_metric();
  Renderer renderer(lib);
  RenderSettings s;
  s.width = s.height = 256;
  std::vector<metrics::Features> features;
  for (const auto& d : lib.shaders())
    features.push_back(metric.features(renderer.render_batch(d, {d.default_packed()}, {1}, s).front()));
  for (size_t i = 0; i < features.size(); ++i)
    for (size_t j = i + 1; j < features.size(); ++j) {
      const double sim = metric.similarity(features[i], features[j]);
      EXPECT_LT(sim, kNearDuplicate) << lib.shaders()[i].name << " and " << lib.shaders()[j].name;
    }
}

TEST(Library, TheMetricSeesTheSameShaderWithAnotherSeedAsCloserThanOtherShaders) {
  // Sanity of the test above: it can fail. A stochastic shader's own re-seeded render must score
  // above the near-duplicate line.
  const auto& metric = metrics::default_metric();
  Renderer renderer;
  RenderSettings s;
  s.width = s.height = 256;
  const ShaderDecl& clouds = ShaderLibrary::builtin().get("clouds");
  const auto a = metric.features(renderer.render_batch(clouds, {clouds.default_packed()}, {1}, s).front());
  const auto b = metric.features(renderer.render_batch(clouds, {clouds.default_packed()}, {2}, s).front());
  EXPECT_GT(metric.similarity(a, b), kNearDuplicate);
}

}  // namespace
}  // namespace proctex
