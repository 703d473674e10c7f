// bench_rgbn: every filter, curvature and view on a 2048^2 RGBN (target < 1 s each on the 2-core
// machine) and stamp / pen edits of a 128^2 footprint (target < 20 ms: the editor calls them on
// every mouse move). The RGBN is the brick photo's luminance as height (x8), tiled to 2048^2.
// Reported: wall-clock per call (Time) and the CPU time of the whole process, all threads (CPU;
// the operators use one thread per core): on a loaded machine CPU is the honest number, and on the
// idle 2-core machine the wall time of a threaded operator is about CPU / 2.
#include <benchmark/benchmark.h>

#include <filesystem>

#include "rgbn/analysis.h"
#include "rgbn/edit.h"
#include "rgbn/filter.h"
#include "rgbn/rgbn.h"
#include "rgbn/view.h"

using namespace proctex;
using namespace proctex::rgbn;

namespace {

const Rgbn& big() {
  static const Rgbn r = [] {
    const Image photo = load_image(std::filesystem::path(PROCTEX_SHARED_DIR) / "textures" / "brick.png");
    const HeightField small = height_from_image(photo);
    HeightField z{2048, 2048, std::vector<float>(size_t(2048) * 2048)};
    for (int y = 0; y < 2048; ++y)
      for (int x = 0; x < 2048; ++x) z.at(x, y) = small.at(x % small.width, y % small.height);
    Rgbn out = from_height(z, 8.0f, true);
    for (int y = 0; y < 2048; ++y)
      for (int x = 0; x < 2048; ++x)
        std::copy(photo.pixel(x % photo.width, y % photo.height), photo.pixel(x % photo.width, y % photo.height) + 3, out.a(x, y));
    return out;
  }();
  return r;
}

void BM_Filter(benchmark::State& state, FilterKind kind) {
  const Rgbn& in = big();
  FilterOptions f;
  f.kind = kind;
  f.sigma = 2, f.sigma2 = 6, f.amount = 1.5f;
  for (auto _ : state) benchmark::DoNotOptimize(filter(in, f));
}
BENCHMARK_CAPTURE(BM_Filter, smooth_s2, FilterKind::Smooth)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(BM_Filter, sharpen_s2, FilterKind::Sharpen)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(BM_Filter, edge_s2_6, FilterKind::Edge)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(BM_Filter, detail_s2_6, FilterKind::Detail)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(BM_Filter, scale, FilterKind::Scale)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_Bilateral(benchmark::State& state) {
  const Rgbn& in = big();
  BilateralOptions b;
  b.sigma_s = float(state.range(0)) / 2;
  for (auto _ : state) benchmark::DoNotOptimize(bilateral(in, b));
}
BENCHMARK(BM_Bilateral)->Arg(2)->Arg(4)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();  // sigma 1, 2

void BM_Curvature(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(curvature(big()));
}
BENCHMARK(BM_Curvature)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_Integrability(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(integrability_error(big()));
}
BENCHMARK(BM_Integrability)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_ViewShaded(benchmark::State& state) {
  ShadeOptions so;
  so.model = state.range(0) ? Shading::BlinnPhong : Shading::Lambert;
  for (auto _ : state) benchmark::DoNotOptimize(shade(big(), so));
}
BENCHMARK(BM_ViewShaded)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_ViewNormals(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(view_normals(big()));
}
BENCHMARK(BM_ViewNormals)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_ViewNeedles(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(view_needles(big(), 16));
}
BENCHMARK(BM_ViewNeedles)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_ViewCurvature(benchmark::State& state) {
  for (auto _ : state) {
    const Curvature c = curvature(big());
    benchmark::DoNotOptimize(view_signed(c.H, 2048, 2048));
  }
}
BENCHMARK(BM_ViewCurvature)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_Segment(benchmark::State& state) {
  const Rgbn& in = big();  // built outside the timed loop (Iterations(1))
  for (auto _ : state) benchmark::DoNotOptimize(segment(in, {}));
}
BENCHMARK(BM_Segment)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);

void BM_Integrate(benchmark::State& state) {
  const Rgbn& in = big();  // built outside the timed loop (Iterations(1))
  for (auto _ : state) benchmark::DoNotOptimize(to_height(in, state.range(0) != 0));
}
BENCHMARK(BM_Integrate)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime()->Iterations(1);

// Edits of a 128^2 footprint on the 2048^2 image (the image is copied once outside the timing;
// the edit is applied repeatedly at alternating places).
void BM_Stamp(benchmark::State& state) {
  Rgbn im = big();
  const nlohmann::json op = {{"op", "stamp"}, {"at", {1000, 1000}}, {"shape", "dome"}, {"radius", 62}, {"height", 12}, {"xi", 10}};
  for (auto _ : state) benchmark::DoNotOptimize(apply_edit(im, op));
}
BENCHMARK(BM_Stamp)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

// The same stamp composed on bilateral-smoothed base normals (sigma 3) of its footprint.
void BM_StampOnBase(benchmark::State& state) {
  Rgbn im = big();
  const nlohmann::json op = {{"op", "stamp"}, {"at", {1000, 1000}}, {"shape", "dome"}, {"radius", 62},
                             {"height", 12}, {"xi", 10}, {"base_sigma", 3}};
  for (auto _ : state) benchmark::DoNotOptimize(apply_edit(im, op));
}
BENCHMARK(BM_StampOnBase)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_StampFile(benchmark::State& state) {
  // A detail stamp cut from the image itself and band-passed: the editor's "clone detail" brush.
  Rgbn im = big();
  static const std::filesystem::path stamp = std::filesystem::temp_directory_path() / "proctex-bench-stamp.exr";
  Rgbn s(128, 128);
  for (int y = 0; y < 128; ++y)
    for (int x = 0; x < 128; ++x) {
      std::copy(big().n(x + 300, y + 300), big().n(x + 300, y + 300) + 3, s.n(x, y));
      std::copy(big().a(x + 300, y + 300), big().a(x + 300, y + 300) + 3, s.a(x, y));
    }
  save_rgbn(s, stamp);
  const nlohmann::json op = {{"op", "stamp"}, {"at", {1000, 1000}}, {"file", stamp.string()}, {"albedo", "keep"}};
  for (auto _ : state) benchmark::DoNotOptimize(apply_edit(im, op));
}
BENCHMARK(BM_StampFile)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_Pen(benchmark::State& state) {
  Rgbn im = big();
  // A 4-segment stroke whose footprint is about 128 x 128 pixels.
  const nlohmann::json op = {{"op", "pen"}, {"points", {{940, 940}, {1000, 1060}, {1040, 960}, {1060, 1050}, {1062, 1060}}},
                             {"width", 6}, {"depth", 2}, {"profile", "vee"}};
  for (auto _ : state) benchmark::DoNotOptimize(apply_edit(im, op));
}
BENCHMARK(BM_Pen)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

void BM_BrushFilter(benchmark::State& state) {
  Rgbn im = big();
  const nlohmann::json op = {{"op", "filter"}, {"filter", "smooth"}, {"sigma", 3}, {"region", {{"disc", {1000, 1000, 64}}, {"feather", 8}}}};
  for (auto _ : state) benchmark::DoNotOptimize(apply_edit(im, op));
}
BENCHMARK(BM_BrushFilter)->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();

}  // namespace

BENCHMARK_MAIN();
