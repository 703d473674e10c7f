// Catalogue build times and adaptive-vs-uniform coverage for every library shader.
//   bench_catalog [--samples N] [--probes P] [--shaders a,b] [--seed S] [--jobs J] [--markdown FILE]
// For each shader: an adaptive build and a uniform build of N samples at 256x256 into scratch
// catalogues, then P random probe vectors (the same for both modes) scored by their best
// similarity to the catalogue. Prints a markdown table (docs/catalog.md, docs/performance.md).
#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "catalog/catalog.h"
#include "core/error.h"
#include "kernels/runtime.h"
#include "shaders/parameter_space.h"

using namespace proctex;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  int samples = 200, probes = 64, jobs = 0;
  uint64_t seed = 1;
  std::string shaders = "all", markdown;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--samples") samples = std::stoi(v);
    else if (a == "--probes") probes = std::stoi(v);
    else if (a == "--shaders") shaders = v;
    else if (a == "--seed") seed = std::stoull(v);
    else if (a == "--jobs") jobs = std::stoi(v);
    else if (a == "--markdown") markdown = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  try {
    const auto& lib = ShaderLibrary::builtin();
    const auto names = catalog::select_shaders(lib, shaders);
    const fs::path scratch = fs::temp_directory_path() / ("proctex-bench-catalog-" + std::to_string(::getpid()));
    fs::create_directories(scratch);
    std::string out = fmt::format(
        "| shader | dims | adaptive build (s) | kept | candidates | adaptive mean / p10 | uniform build (s) | uniform mean / p10 | mean gain | p10 gain |\n"
        "|---|---|---|---|---|---|---|---|---|---|\n");
    int wins_mean = 0, wins_p10 = 0;
    double total_adaptive = 0;
    std::vector<double> times;
    for (const auto& name : names) {
      catalog::Coverage cov[2];
      double secs[2];
      int kept = 0;
      long candidates = 0;
      for (int m = 0; m < 2; ++m) {
        catalog::BuildOptions o;
        o.db = scratch / (name + (m ? "-u" : "-a") + ".sqlite");
        o.shaders = {name};
        o.seed = seed;
        o.jobs = jobs;
        o.settings.samples = samples;
        o.settings.probes = probes;
        o.settings.mode = m ? "uniform" : "adaptive";
        const auto r = catalog::build(o);
        cov[m] = r.shaders.at(0).coverage.value_or(catalog::Coverage{});
        secs[m] = r.shaders.at(0).seconds;
        if (m == 0) {
          kept = r.shaders[0].samples;
          candidates = r.shaders[0].stats.value("candidates", 0L);
        }
      }
      total_adaptive += secs[0];
      times.push_back(secs[0]);
      wins_mean += cov[0].mean > cov[1].mean;
      wins_p10 += cov[0].p10 > cov[1].p10;
      const std::string row = fmt::format(
          "| {} | {} | {:.1f} | {} | {} | {:.3f} / {:.3f} | {:.1f} | {:.3f} / {:.3f} | {:+.1f}% | {:+.1f}% |\n", name,
          ParameterSpace(lib.get(name)).dimensions(), secs[0], kept, candidates, cov[0].mean, cov[0].p10, secs[1],
          cov[1].mean, cov[1].p10, 100.0 * (cov[0].mean / cov[1].mean - 1.0), 100.0 * (cov[0].p10 / cov[1].p10 - 1.0));
      std::printf("%s", row.c_str());
      std::fflush(stdout);
      out += row;
    }
    std::sort(times.begin(), times.end());
    const std::string summary = fmt::format(
        "\n{} shaders, N = {}, {} probes, 256x256, device {}: adaptive beats uniform on mean coverage for {}, on p10 for {}; "
        "adaptive build median {:.1f} s, max {:.1f} s, total {:.0f} s.\n",
        names.size(), samples, probes, ocl::Runtime::instance().device().name, wins_mean, wins_p10,
        times[times.size() / 2], times.back(), total_adaptive);
    std::printf("%s", summary.c_str());
    out += summary;
    if (!markdown.empty()) std::ofstream(markdown) << out;
    fs::remove_all(scratch);
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_catalog: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
