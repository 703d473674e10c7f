// Google Benchmark: features() per metric for a 256 x 256 image (target: a few ms), the
// analysis preparation alone, and one similarity evaluation of the default metric.
#include <benchmark/benchmark.h>

#include "image/image.h"
#include "metrics/metric.h"

using namespace proctex;

namespace {

const Image& sample() {
#ifdef PROCTEX_SHARED_DIR
  static const Image img = crop(load_image(std::string(PROCTEX_SHARED_DIR) + "/textures/brick.png"), 0, 0, 256, 256);
#else
  static const Image img(256, 256, 0.5f);
#endif
  return img;
}

void BM_Prepare(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(metrics::prepare_analysis(sample(), 256));
}
BENCHMARK(BM_Prepare)->Unit(benchmark::kMillisecond);

void BM_Features(benchmark::State& state, const char* name) {
  const metrics::Metric& m = metrics::get_metric(name);
  m.features(sample());  // plans and filter banks
  for (auto _ : state) benchmark::DoNotOptimize(m.features(sample()));
}
BENCHMARK_CAPTURE(BM_Features, spectrum, "spectrum")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Features, pyramid, "pyramid")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Features, colour, "colour")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Features, structure, "structure")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Features, composite, "composite")->Unit(benchmark::kMillisecond);

// The refinement's resolution (search::MatchOptions::coarse_resolution): a match computes these
// features once per render, between renders, so they add to a match's wall time.
void BM_FeaturesAt128(benchmark::State& state) {
  const metrics::Metric& m = metrics::default_metric();
  m.features(sample(), 128);
  for (auto _ : state) benchmark::DoNotOptimize(m.features(sample(), 128));
}
BENCHMARK(BM_FeaturesAt128)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Features1024(benchmark::State& state) {
  // A 1024 x 1024 input: the resize to the analysis resolution is part of the cost.
  const Image big = resize(sample(), 1024, 1024);
  const metrics::Metric& m = metrics::default_metric();
  for (auto _ : state) benchmark::DoNotOptimize(m.features(big));
}
BENCHMARK(BM_Features1024)->Unit(benchmark::kMillisecond);

void BM_Similarity(benchmark::State& state) {
  const metrics::Metric& m = metrics::default_metric();
  const auto a = m.features(sample()).values;
  auto b = a;
  b[0] += 0.1f;
  for (auto _ : state) benchmark::DoNotOptimize(m.similarity(a, b));
}
BENCHMARK(BM_Similarity)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
