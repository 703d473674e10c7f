// PNG writing (image/save_image) of 512x512 renders: what a morph pays per frame and a match per
// --render. Reproduces the numbers of docs/performance.md ("Morph", PNG writer).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <string>

#include "image/image.h"
#include "shaders/renderer.h"

using namespace proctex;

namespace {

const Image& render_512(const std::string& spec) {
  static std::map<std::string, Image> cache;
  auto it = cache.find(spec);
  if (it == cache.end()) {
    Renderer renderer;
    RenderSettings s;
    s.width = s.height = 512;
    it = cache.emplace(spec, renderer.render(parse_spec_argument(spec), s)).first;
  }
  return it->second;
}

void BM_SavePng(benchmark::State& state, const char* spec) {
  const Image& img = render_512(spec);
  const auto path = std::filesystem::temp_directory_path() / "proctex-bench-save.png";
  for (auto _ : state) save_image(img, path);
  state.counters["bytes"] = double(std::filesystem::file_size(path));
  std::filesystem::remove(path);
}
BENCHMARK_CAPTURE(BM_SavePng, bricks, "bricks")->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_SavePng, clouds, "clouds")->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
