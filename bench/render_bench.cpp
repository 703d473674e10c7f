// Render throughput per shader at 256x256 on the OpenCL device: one image per launch (what a
// single render costs) and 16 per launch (what the catalogue and the search use).
//   build/bench/bench_render [--markdown FILE] [google-benchmark flags]
// A/B mode for optimising shaders on a shared, noisy machine: renders the shaders found in two
// folders (same file names, e.g. before/ and after/ copies) in alternation, many short rounds, and
// reports median and minimum per image for each side. Without DIR_B it times the built-in library
// the same way (interleaved rounds over all shaders; robust to load drifting during the run).
//   build/bench/bench_render --ab DIR_A [DIR_B] [--rounds N] [--reps K] [--only a,b,c]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <sstream>
#include <set>
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

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

double process_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// Milliseconds per image of `reps` single-image renders: wall-clock time, and the CPU time of all
// the process's threads (PoCL's workers included), which other processes' load disturbs much less.
struct Timing {
  double wall, cpu;
};
Timing time_renders(Renderer& renderer, const ShaderDecl& decl, int reps) {
  RenderSettings s;
  s.width = s.height = 256;
  const std::vector<std::vector<float>> params(1, decl.default_packed());
  const std::vector<uint32_t> seeds(1, 0);
  const double c0 = process_cpu_ms();
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < reps; ++i) benchmark::DoNotOptimize(renderer.render_batch(decl, params, seeds, s));
  const double wall = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return {wall / reps, (process_cpu_ms() - c0) / reps};
}

int run_ab(const std::string& dir_a, const std::string& dir_b, int rounds, int reps, const std::string& only) {
  const ShaderLibrary lib_a = dir_a == "builtin" ? ShaderLibrary::builtin() : ShaderLibrary::from_directory(dir_a);
  const ShaderLibrary lib_b = dir_b.empty() ? ShaderLibrary() : ShaderLibrary::from_directory(dir_b);
  std::set<std::string> wanted;
  std::stringstream names(only);
  for (std::string n; std::getline(names, n, ',');)
    if (!n.empty()) wanted.insert(n);
  struct Entry {
    std::string name;
    const ShaderDecl* a;
    const ShaderDecl* b;
    std::vector<double> ta, tb, ca, cb;  // wall and CPU ms per image, one entry per round
  };
  std::vector<Entry> entries;
  for (const auto& d : lib_a.shaders()) {
    if (!wanted.empty() && !wanted.count(d.name)) continue;
    const ShaderDecl* b = dir_b.empty() ? nullptr : lib_b.find(d.name);
    if (!dir_b.empty() && !b) continue;
    entries.push_back({d.name, &d, b, {}, {}, {}, {}});
  }
  Renderer ra(lib_a), rb(lib_b);
  for (auto& e : entries) {  // build + PoCL's first-launch compile, outside the timing
    time_renders(ra, *e.a, 1);
    if (e.b) time_renders(rb, *e.b, 1);
  }
  auto run = [&](Renderer& r, const ShaderDecl& d, std::vector<double>& wall, std::vector<double>& cpu) {
    const Timing t = time_renders(r, d, reps);
    wall.push_back(t.wall);
    cpu.push_back(t.cpu);
  };
  for (int r = 0; r < rounds; ++r)
    for (auto& e : entries) {
      if (!e.b) {
        run(ra, *e.a, e.ta, e.ca);
      } else if (r % 2 == 0) {  // alternate which side goes first
        run(ra, *e.a, e.ta, e.ca);
        run(rb, *e.b, e.tb, e.cb);
      } else {
        run(rb, *e.b, e.tb, e.cb);
        run(ra, *e.a, e.ta, e.ca);
      }
    }
  auto lo = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  std::printf("%d rounds x %d renders, ms per 256x256 image (1 per launch); wall clock and process CPU time\n",
              rounds, reps);
  if (dir_b.empty()) {
    std::printf("%-16s %9s %9s %9s %9s\n", "shader", "wall med", "wall min", "cpu med", "cpu min");
    std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) { return median(x.ta) > median(y.ta); });
    for (const auto& e : entries)
      std::printf("%-16s %9.2f %9.2f %9.2f %9.2f\n", e.name.c_str(), median(e.ta), lo(e.ta), median(e.ca), lo(e.ca));
    return 0;
  }
  std::printf("%-16s %8s %8s %8s %8s %6s %6s | %8s %8s %6s %6s\n", "shader", "A med", "B med", "A min", "B min",
              "B/A", "B wins", "A cpu", "B cpu", "B/A", "B wins");
  for (const auto& e : entries) {
    int wins = 0, cpu_wins = 0;
    for (size_t i = 0; i < e.ta.size(); ++i) {
      wins += e.tb[i] < e.ta[i];
      cpu_wins += e.cb[i] < e.ca[i];
    }
    const int n = static_cast<int>(e.ta.size());
    std::printf("%-16s %8.2f %8.2f %8.2f %8.2f %6.3f %3d/%-2d | %8.2f %8.2f %6.3f %3d/%-2d\n", e.name.c_str(),
                median(e.ta), median(e.tb), lo(e.ta), lo(e.tb), median(e.tb) / median(e.ta), wins, n, median(e.ca),
                median(e.cb), median(e.cb) / median(e.ca), cpu_wins, n);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string markdown;
  std::vector<char*> args;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--markdown") == 0 && i + 1 < argc) markdown = argv[++i];
    else args.push_back(argv[i]);
  }
  if (argc > 2 && std::strcmp(argv[1], "--ab") == 0) {
    std::string dir_a = argv[2], dir_b, only;
    int rounds = 15, reps = 5;
    for (int i = 3; i < argc; ++i) {
      if (std::strcmp(argv[i], "--rounds") == 0 && i + 1 < argc) rounds = std::atoi(argv[++i]);
      else if (std::strcmp(argv[i], "--reps") == 0 && i + 1 < argc) reps = std::atoi(argv[++i]);
      else if (std::strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
      else if (argv[i][0] != '-' && dir_b.empty()) dir_b = argv[i];
    }
    return run_ab(dir_a, dir_b, std::max(rounds, 1), std::max(reps, 1), only);
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
