// Evaluation of `proctex match` (issue 6): synthetic recovery and real photos.
//   bench_match_eval --db CATALOG [--targets N] [--seed S] [--photos DIR] [--pictures DIR]
//                    [--markdown FILE] [--shaders a,b] [--evaluations E] [--starts K]
//                    [--candidates M] [--screen-resolution R] [--race R]
// Synthetic: N targets, target i from shader i mod L of the library (sorted by name) at a random
// point of its unit parameter space (a portable random stream from --seed, so not a catalogue
// sample) rendered at 256x256 with render seed 7000000 + i (the catalogue's render seeds are
// drawn from its own stream). Each target is matched against the whole catalogue with the
// default options. Reported: shader identified (top-1), the target shader's rank in the structural
// scan of the catalogue (what --candidates cuts), final similarity, verdict, time; for
// deterministic shaders (two render seeds give the same image) the parameter error: mean
// |unit difference| over the searchable dimensions and whether every discrete parameter is exact.
// Photos: every image in --photos is matched, with a side-by-side picture in --pictures.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "catalog/store.h"
#include "core/error.h"
#include "search/match.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"

using namespace proctex;
namespace fs = std::filesystem;

namespace {

// SplitMix64: portable, so the targets are the same on every machine.
struct Random {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double unit() { return double(next() >> 11) * 0x1.0p-53; }
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

bool deterministic(Renderer& r, const ShaderDecl& decl, const std::vector<float>& packed) {
  RenderSettings s;
  s.width = s.height = 64;
  const auto imgs = r.render_batch(decl, {packed, packed}, {11u, 987654u}, s);
  return imgs[0].pixels == imgs[1].pixels;
}

Image side_by_side_tile(const Image& img, int side) { return resize(center_crop_square(img), side, side); }

}  // namespace

int main(int argc, char** argv) {
  std::string db, photos, pictures, markdown, only;
  int targets = 53, starts = -1, candidates = -1, screen_resolution = -1, race = -1;
  long evaluations = -1;
  uint64_t seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::puts("bench_match_eval --db CATALOG [--targets N] [--seed S] [--photos DIR] [--pictures DIR] "
                "[--markdown FILE] [--shaders a,b] [--evaluations E] [--starts K] [--candidates M] "
                "[--screen-resolution R] [--race R]");
      return 0;
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "option %s needs a value\n", a.c_str());
      return 2;
    }
    const std::string v = argv[++i];
    if (a == "--db") db = v;
    else if (a == "--targets") targets = std::stoi(v);
    else if (a == "--seed") seed = std::stoull(v);
    else if (a == "--photos") photos = v;
    else if (a == "--pictures") pictures = v;
    else if (a == "--markdown") markdown = v;
    else if (a == "--shaders") only = v;
    else if (a == "--evaluations") evaluations = std::stol(v);
    else if (a == "--starts") starts = std::stoi(v);
    else if (a == "--candidates") candidates = std::stoi(v);
    else if (a == "--race") race = std::stoi(v);
    else if (a == "--screen-resolution") screen_resolution = std::stoi(v);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (db.empty()) {
    std::fprintf(stderr, "--db CATALOG is required\n");
    return 2;
  }
  try {
    const auto& lib = ShaderLibrary::builtin();
    catalog::Store store(db, catalog::Store::Access::Read);
    std::vector<std::string> names;
    for (const auto& s : store.shaders()) names.push_back(s.name);
    std::sort(names.begin(), names.end());
    if (!only.empty()) {
      std::vector<std::string> keep;
      for (const auto& n : names)
        if (("," + only + ",").find("," + n + ",") != std::string::npos) keep.push_back(n);
      names = keep;
    }
    search::MatchOptions options;
    if (evaluations > 0) options.refine.max_evaluations = evaluations;
    if (starts > 0) options.starts = starts;
    if (candidates >= 0) options.candidate_shaders = candidates;
    if (race > 0) options.race = race;
    if (screen_resolution > 0) options.screen_resolution = screen_resolution;
    if (!pictures.empty()) fs::create_directories(pictures);
    Renderer renderer(lib);
    Random rng{seed};

    std::string table =
        "| # | target shader | structural rank | matched | S | verdict | time (s) | renders | param error | discrete "
        "exact |\n|---|---|---|---|---|---|---|---|---|---|\n";
    std::vector<double> sims, times, param_errors, ranks;
    int identified = 0, det_total = 0, det_exact = 0, good = 0, approximate = 0;
    std::vector<Image> tiles;
    std::vector<std::string> labels;
    for (int i = 0; i < targets; ++i) {
      const ShaderDecl& decl = lib.get(names[i % names.size()]);
      const ParameterSpace space(decl);
      std::vector<double> unit(space.dimensions());
      for (auto& u : unit) u = rng.unit();
      unit = space.snap(unit);
      const auto packed = space.to_packed(unit);
      const uint32_t render_seed = 7000000u + i;
      RenderSettings rs;
      const Image target = renderer.render_batch(decl, {packed}, {render_seed}, rs).front();
      const auto t0 = std::chrono::steady_clock::now();
      const auto r = search::match(target, store, options);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const bool hit = r.spec.shader == decl.name;
      // Rank of the target's shader among the screened candidates by structure (1 = first); past
      // the candidates when it was cut.
      auto by_structure = r.candidates;
      std::sort(by_structure.begin(), by_structure.end(),
                [](const auto& a, const auto& b) { return a.best_full > b.best_full; });
      const auto found = std::find_if(by_structure.begin(), by_structure.end(),
                                      [&](const auto& c) { return c.shader == decl.name; });
      const std::string rank = found == by_structure.end() ? fmt::format(">{}", by_structure.size())
                                                           : std::to_string(found - by_structure.begin() + 1);
      ranks.push_back(found == by_structure.end() ? 1e9 : double(found - by_structure.begin() + 1));
      identified += hit;
      good += r.verdict == "good";
      approximate += r.verdict == "approximate";
      sims.push_back(r.similarity);
      times.push_back(secs);
      std::string err = "-", exact = "-";
      if (deterministic(renderer, decl, packed)) {
        ++det_total;
        if (hit) {
          const auto matched = space.to_unit(resolve(decl, r.spec));
          double sum = 0;
          bool all_exact = true;
          for (size_t d = 0; d < unit.size(); ++d) {
            sum += std::fabs(matched[d] - unit[d]);
            if (space.dims()[d].levels && std::fabs(matched[d] - unit[d]) > 1e-6) all_exact = false;
          }
          const double e = unit.empty() ? 0.0 : sum / unit.size();
          param_errors.push_back(e);
          det_exact += all_exact;
          err = fmt::format("{:.3f}", e);
          exact = all_exact ? "yes" : "no";
        } else {
          exact = "no";
        }
      }
      table += fmt::format("| {} | {} | {} | {} | {:.3f} | {} | {:.1f} | {} | {} | {} |\n", i + 1, decl.name, rank, r.spec.shader,
                           r.similarity, r.verdict, secs, r.evaluations, err, exact);
      std::fprintf(stderr, "%2d/%d %-14s (rank %s) -> %-14s S=%.3f %-11s %.1f s\n", i + 1, targets, decl.name.c_str(),
                   rank.c_str(), r.spec.shader.c_str(), r.similarity, r.verdict.c_str(), secs);
      if (!pictures.empty()) {  // the whole result, to see where a miss was lost (scan, screen, race)
        nlohmann::json j = r.to_json();
        j["target"] = {{"spec", spec_from_packed(decl, packed, render_seed).to_json()}, {"seconds", secs}};
        std::ofstream(fs::path(pictures) / fmt::format("{:02d}-{}.json", i + 1, decl.name)) << j.dump(1) << "\n";
      }
      if (!pictures.empty() && tiles.size() < 64) {
        RenderSettings small;
        small.width = small.height = 128;
        tiles.push_back(side_by_side_tile(target, 128));
        labels.push_back(fmt::format("{} target", decl.name));
        tiles.push_back(renderer.render(r.spec, small));
        labels.push_back(fmt::format("{} {:.2f}", r.spec.shader, r.similarity));
      }
    }
    if (!pictures.empty() && !tiles.empty())
      save_image(contact_sheet(tiles, labels, 8, 128), fs::path(pictures) / "synthetic.jpg");
    const double worst = times.empty() ? NAN : *std::max_element(times.begin(), times.end());
    std::string summary = fmt::format(
        "Synthetic recovery: {} targets, shader identified {}/{} ({:.0f}%), target shader among the first 1 / 5 / "
        "12 of the structural scan {} / {} / {}, median S {:.3f}, verdicts good {} / "
        "approximate {} / no-match {}; deterministic targets {}: all discrete parameters exact {}, median "
        "parameter error {:.3f} (mean |unit difference|, identified ones); time per match median {:.1f} s, worst "
        "{:.1f} s.\n\n",
        targets, identified, targets, 100.0 * identified / std::max(1, targets),
        std::count_if(ranks.begin(), ranks.end(), [](double r) { return r <= 1; }),
        std::count_if(ranks.begin(), ranks.end(), [](double r) { return r <= 5; }),
        std::count_if(ranks.begin(), ranks.end(), [](double r) { return r <= 12; }), median(sims), good, approximate,
        targets - good - approximate, det_total, det_exact, median(param_errors), median(times), worst);

    std::string photo_table;
    if (!photos.empty()) {
      photo_table = "| photo | matched | S | verdict | time (s) | renders | picture |\n|---|---|---|---|---|---|---|\n";
      std::vector<fs::path> files;
      for (const auto& e : fs::directory_iterator(photos)) {
        const auto ext = e.path().extension().string();
        if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif") files.push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      for (const auto& f : files) {
        const Image target = search::prepare_target(f, "");
        const auto t0 = std::chrono::steady_clock::now();
        const auto r = search::match(target, store, options);
        const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::string pic = "-";
        if (!pictures.empty()) {
          RenderSettings s;
          s.width = s.height = 384;
          const Image m = renderer.render(r.spec, s);
          const fs::path out = fs::path(pictures) / (f.stem().string() + ".jpg");
          save_image(contact_sheet({side_by_side_tile(target, 384), m},
                                   {f.filename().string(), fmt::format("{} S={:.2f} ({})", r.spec.shader, r.similarity, r.verdict)},
                                   2, 384),
                     out);
          pic = out.string();
        }
        photo_table += fmt::format("| {} | {} | {:.3f} | {} | {:.1f} | {} | {} |\n", f.filename().string(), r.spec.shader,
                                   r.similarity, r.verdict, secs, r.evaluations, pic);
        std::fprintf(stderr, "%s -> %s S=%.3f %s %.1f s\n", f.filename().c_str(), r.spec.shader.c_str(), r.similarity,
                     r.verdict.c_str(), secs);
      }
    }
    const std::string report = summary + table + "\n" + photo_table;
    std::fputs(report.c_str(), stdout);
    if (!markdown.empty()) std::ofstream(markdown) << report;
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_match_eval: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
