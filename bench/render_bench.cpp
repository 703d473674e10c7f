// Render throughput per shader at 256x256 on the OpenCL device: one image per launch (what a
// single render costs) and 16 per launch (what the catalogue and the search use).
//   build/bench/bench_render [--markdown FILE] [google-benchmark flags]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>

#include "kernels/runtime.h"
#include "shaders/library.h"
#include "shaders/renderer.h"

namespace {

using namespace proctex;

void render_shader(benchmark::State& state, const ShaderDecl* decl, int batch) {
  Renderer renderer;
  RenderSettings s;
  s.width = s.height = 256;
  const std::vector<std::vector<float>> params(batch, decl->default_packed());
  std::vector<uint32_t> seeds(batch);
  for (int i = 0; i < batch; ++i) seeds[i] = i;
  // Compile outside the timing: the program build, and PoCL's lazy per-launch-shape work-group
  // compile on the first enqueue (60-110 ms, which inflated earlier tables).
  renderer.render_batch(*decl, params, seeds, s);
  for (auto _ : state) benchmark::DoNotOptimize(renderer.render_batch(*decl, params, seeds, s));
  state.SetItemsProcessed(state.iterations() * batch);
}

// Collects the median of each benchmark's repetitions for the markdown table.
class TableReporter : public benchmark::ConsoleReporter {
 public:
  std::map<std::string, std::map<int, double>> images_per_second;  // shader -> batch -> img/s
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const auto& r : runs) {
      if (r.aggregate_name != "median") continue;
      const std::string name = r.run_name.function_name;  // render/<shader>/<batch>
      const auto a = name.find('/'), b = name.rfind('/');
      const auto it = r.counters.find("items_per_second");
      if (it == r.counters.end()) continue;
      images_per_second[name.substr(a + 1, b - a - 1)][std::stoi(name.substr(b + 1))] = it->second;
    }
  }
};

}  // namespace

int main(int argc, char** argv) {
  std::string markdown;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--markdown") == 0 && i + 1 < argc) markdown = argv[++i];
    else args.push_back(argv[i]);
  }
  int n = static_cast<int>(args.size());
  for (const auto& d : ShaderLibrary::builtin().shaders())
    for (int batch : {1, 16})
      benchmark::RegisterBenchmark(("render/" + d.name + "/" + std::to_string(batch)).c_str(), render_shader, &d, batch)
          ->Unit(benchmark::kMillisecond)
          ->Repetitions(3)
          ->ReportAggregatesOnly(true)
          ->UseRealTime();
  benchmark::Initialize(&n, args.data());
  TableReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  if (!markdown.empty()) {
    std::ofstream out(markdown);
    out << "Device: " << ocl::Runtime::instance().device().name << "\n\n";
    out << "| shader | ms per image (1 per launch) | images/s (1 per launch) | images/s (16 per launch) |\n";
    out << "|---|---:|---:|---:|\n";
    for (const auto& [shader, by_batch] : reporter.images_per_second) {
      const double one = by_batch.count(1) ? by_batch.at(1) : 0, sixteen = by_batch.count(16) ? by_batch.at(16) : 0;
      char line[256];
      std::snprintf(line, sizeof line, "| %s | %.1f | %.0f | %.0f |\n", shader.c_str(), one > 0 ? 1000.0 / one : 0.0,
                    one, sixteen);
      out << line;
    }
  }
  benchmark::Shutdown();
  return 0;
}
