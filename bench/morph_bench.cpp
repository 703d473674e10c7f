// Morph benchmark (issue 7): 120 frames at 512x512 within one shader, end to end through the CLI
// (plan + quality report with the linear baseline + frame renders + PNG writes + sheet + manifest).
//   bench_morph [--shader bricks] [--from SPEC] [--to SPEC] [--frames 120] [--size 512]
//               [--repetitions 3] [--db FILE] [--markdown FILE]
// Without --db a scratch catalogue of the shader is built first (default settings, not timed).
// Target: at most 30 s per run on the 2-core development machine.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "catalog/catalog.h"
#include "core/error.h"

using namespace proctex;
namespace fs = std::filesystem;

int main(int argc, char** argv) {
  std::string shader = "bricks", from = "bricks:rows=4,mortar=0.03,wear=0.1,seed=1",
              to = "bricks:rows=24,mortar=0.25,wear=0.9,variation=0.9,seed=1", db, markdown;
  int frames = 120, size = 512, repetitions = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--shader") shader = v;
    else if (a == "--from") from = v;
    else if (a == "--to") to = v;
    else if (a == "--frames") frames = std::stoi(v);
    else if (a == "--size") size = std::stoi(v);
    else if (a == "--repetitions") repetitions = std::stoi(v);
    else if (a == "--db") db = v;
    else if (a == "--markdown") markdown = v;
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  try {
    const fs::path scratch = fs::temp_directory_path() / ("proctex-bench-morph-" + std::to_string(::getpid()));
    fs::create_directories(scratch);
    if (db.empty()) {
      db = (scratch / "catalog.sqlite").string();
      catalog::BuildOptions o;
      o.db = db;
      o.shaders = {shader};
      o.settings.probes = 0;
      std::fprintf(stderr, "building a %s catalogue (not timed)...\n", shader.c_str());
      catalog::build(o);
    }
    const std::string cmd = fmt::format("'{}' -q morph '{}' '{}' --db '{}' --frames {} --size {} -o '{}' --json > '{}'",
                                        PROCTEX_BINARY, from, to, db, frames, size, (scratch / "frames").string(),
                                        (scratch / "out.json").string());
    std::vector<double> wall;
    nlohmann::json last;
    for (int r = 0; r < repetitions; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      if (std::system(cmd.c_str()) != 0) throw Error("proctex morph failed: " + cmd);
      wall.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      std::ifstream in(scratch / "out.json");
      last = nlohmann::json::parse(in);
      std::fprintf(stderr, "run %d: %.2f s\n", r + 1, wall.back());
    }
    std::vector<double> sorted = wall;
    std::sort(sorted.begin(), sorted.end());
    const auto& t = last["timings"];
    const auto& q = last["quality"];
    std::string row = fmt::format(
        "| {} | {} | {}x{} | {:.1f} | {:.1f} | {:.1f} / {:.1f} / {:.1f} / {:.1f} | {:.3f} / {:.3f} | {} |\n", shader,
        frames, size, size, sorted.front(), sorted[sorted.size() / 2], t.value("plan", 0.0), t.value("measure", 0.0),
        t.value("frames", 0.0), t.value("total", 0.0), q["morph"]["max_dissimilarity"].get<double>(),
        q.contains("linear") ? q["linear"]["max_dissimilarity"].get<double>() : 0.0, repetitions);
    const std::string table =
        "| shader | frames | size | best (s) | median (s) | plan / measure / frames / total of last run (s) | max 1-S morph / linear | runs |\n"
        "|---|---|---|---|---|---|---|---|\n" + row;
    std::printf("%s", table.c_str());
    if (!markdown.empty()) std::ofstream(markdown) << table;
    fs::remove_all(scratch);
    std::printf("target (median <= 30 s): %s\n", sorted[sorted.size() / 2] <= 30.0 ? "met" : "missed");
    return 0;
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_morph: %s\n", e.message().c_str());
    return 1;
  }
}
