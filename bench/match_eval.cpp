// Evaluation of `proctex match` (issue 6): synthetic recovery and real photos.
//   bench_match_eval --db CATALOG [--targets N] [--seed S] [--photos DIR] [--pictures DIR]
//                    [--markdown FILE] [--shaders a,b] [--evaluations E] [--starts K]
//                    [--candidates M] [--screen-resolution R] [--race R]
//                    [--real LABELS [--split tune|report|all] [--real-images DIR]] [--json FILE]
// Synthetic: N targets, target i from shader i mod L of the library (sorted by name) at a random
// point of its unit parameter space (a portable random stream of its own, from --seed, the
// shader's name and i - so not a catalogue sample, and a shader's new parameter redraws only
// that shader's targets) rendered at 256x256 with render seed 7000000 + i (the catalogue's render seeds are
// drawn from its own stream). Each target is matched against the whole catalogue with the
// default options. Reported: shader identified (top-1), the target shader's rank in the structural
// scan of the catalogue (what --candidates cuts), final similarity, verdict, time; for
// deterministic shaders (two render seeds give the same image) the parameter error: mean
// |unit difference| over the searchable dimensions, whether every discrete parameter is exact,
// whether all are (issue 12: discrete exact and every continuous one within 2% of its range; a
// parameter with a declared symmetry period compared modulo it, as shader metadata says), and
// the image's RMS difference at the best whole-pixel shift (aliases that render the same image).
// Photos: every image in --photos is matched, with a side-by-side picture in --pictures.
// Noise ceiling (synthetic): the target's spec rendered with other render seeds (+1, 2, 3 x 10^6),
// compared with the target under the default metric at the match resolution, mean of the 3: what
// the exact spec scores against this instance (1 for deterministic shaders; a match refined on the
// instance can exceed it). "reproduced" = shader identified or S >= 0.95 x ceiling.
// Real set (--real LABELS, issue 12): every image of --split (tune|report|all) of the labelled
// set (bench/realset/labels.json, images built by bench/realset/build.py into --real-images) is
// matched. Reported: category accuracy (matched shader among the image's accepted shaders), top-3
// accuracy of the result's shader ranking (the matched shader, then the candidates in the
// selection's order), the share of wrong-category results called `good`, and the precision of `good`.
// With --pictures: <id>.jpg (photo | match render), real-<split>.jpg (all pairs) and <id>.json
// (the whole match result with the label and the scores); --json FILE: summary + per-image rows.
#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <array>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "catalog/catalog.h"
#include "catalog/store.h"
#include "core/error.h"
#include "core/hash.h"
#include "metrics/metric.h"
#include "search/match.h"
#include "shaders/library.h"
#include "shaders/parameter_space.h"
#include "shaders/renderer.h"

using namespace proctex;
namespace fs = std::filesystem;

namespace {

// How far a match's render is from a deterministic target as an image: RMS linear-RGB difference
// on the overlap at the best whole-pixel shift within +-kImageShift px (a pattern that starts
// elsewhere - a checker with its colours swapped, stripes with the complementary duty in swapped
// colours - is the same texture; the overlap, not a wrap-around, because few patterns are periodic
// on the image). Such aliases count as exact here, not in the parameters.
// The product's "pixel-exact" threshold (search/match.h, kPixelExactRmse), measured independently
// here (brute force over shifts): 0.01 let a soft 8-pointed star pass as a disc.
constexpr double kImageExactRmse = 0.005;
constexpr int kImageShift = 24;

// RGB RMSE of b(x + dx, y + dy) against a(x, y) on the overlap.
double rmse_at(const Image& a, const Image& b, int dx, int dy) {
  const int w = a.width, h = a.height;
  double sum = 0;
  for (int y = std::max(0, -dy); y < std::min(h, h - dy); ++y)
    for (int x = std::max(0, -dx); x < std::min(w, w - dx); ++x) {
      const float* p = a.pixel(x, y);
      const float* q = b.pixel(x + dx, y + dy);
      for (int c = 0; c < 3; ++c) sum += double(p[c] - q[c]) * (p[c] - q[c]);
    }
  return std::sqrt(sum / (3.0 * (w - std::abs(dx)) * (h - std::abs(dy))));
}

// The smallest rmse_at over whole-pixel shifts within +-kImageShift.
double shifted_rmse(const Image& a, const Image& b) {
  double best = 1e30;
  for (int dy = -kImageShift; dy <= kImageShift && best > 0; ++dy)
    for (int dx = -kImageShift; dx <= kImageShift && best > 0; ++dx) best = std::min(best, rmse_at(a, b, dx, dy));
  return best;
}

// SplitMix64: portable, so the targets are the same on every machine.
struct Random {
  // Target i's own stream, from --seed, the shader's name and i: a parameter added to one shader
  // redraws only that shader's targets (one stream for all targets, as before session 19, redrew
  // every target after it, so two library versions were not measured on the same test).
  static Random for_target(uint64_t seed, const std::string& shader, int i) {
    Random r{seed ^ std::stoull(fnv1a_hex(shader), nullptr, 16)};
    r.state ^= r.next() + static_cast<uint64_t>(i);
    return r;
  }
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

// CPU seconds of this process so far (user + system, every thread: PoCL's workers included). Under
// load a match's wall time is inflated by the other processes; its CPU time much less.
double process_cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

Image side_by_side_tile(const Image& img, int side) { return resize(center_crop_square(img), side, side); }

// The match result's shader ranking: the finalists by their final similarity (the matched shader
// first), then the other raced starts by their coarse similarity, then the screened candidates;
// each shader once.
// The result's shader ranking: the matched shader, then the candidates in the selection's order
// (search/selection.h: most likely material first).
std::vector<std::string> shader_ranking(const search::MatchResult& r) {
  std::vector<std::string> out;
  auto add = [&](const std::string& s) {
    if (!s.empty() && std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  };
  add(r.spec.shader);
  for (const auto& c : r.candidates) add(c.shader);
  return out;
}

std::string join(const std::vector<std::string>& v, const char* sep = ", ") {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : sep) + s;
  return out;
}

std::string percent(int a, int b) { return b ? fmt::format("{}/{} ({:.0f}%)", a, b, 100.0 * a / b) : "0/0 (-)"; }

}  // namespace

int main(int argc, char** argv) {
  std::string db, photos, pictures, markdown, only, real, split = "tune", real_images = "build/realset/images", json_out,
      override_file;
  int targets = -1, starts = -1, candidates = -1, screen_resolution = -1, race = -1, threads = 0;
  bool refine_every = false, polish_every = false, race_every = false;
  long evaluations = -1;
  uint64_t seed = 1;
  std::set<int> only_targets;  // 1-based; empty: every target
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::puts("bench_match_eval --db CATALOG [--targets N] [--seed S] [--photos DIR] [--pictures DIR] "
                "[--markdown FILE] [--shaders a,b] [--evaluations E] [--starts K] [--candidates M] "
                "[--screen-resolution R] [--race R] [--real LABELS [--split tune|report|all] [--real-images DIR]] "
                "[--json FILE] [--selection-override FILE] [--threads T] [--refine-every-finalist 1] [--polish-every-finalist 1] [--race-every-lane 1] [--only 7,25]\n"
                "  --targets N      synthetic targets (default 53, or 0 with --real)\n"
                "  --real LABELS    labelled real-texture set (bench/realset/labels.json; build the images with\n"
                "                   python3 bench/realset/build.py): category / top-3 accuracy, wrong-but-good share\n"
                "  --split S        tune (default), report or all\n"
                "  --real-images D  folder of <id>.png (default build/realset/images)\n"
                "  --json FILE      summary and per-image rows as JSON\n"
                "  --selection-override FILE\n"
                "                   {photo id: {shader: probability}}: the selection's probabilities of these photos\n"
                "                   (bench/fit_selection.py --oof-json: out-of-fold, for photos the model was trained on)\n"
                "  --only LIST      match only these synthetic targets (1-based numbers, as the table's #); the\n"
                "                   others are still drawn, so each target is the one of the full run\n"
                "  --threads T      host threads of the race (default 0: one per core; 1 as before session 13)\n"
                "  --refine-every-finalist 1\n"
                "                   refine the finalists that cannot win too (as before session 13: same answers)\n"
                "  --polish-every-finalist 1\n"
                "                   on clean patterns, also polish the finalists whose polish cannot change the choice\n"
                "                   (shaders that are not deterministic; as before session 14)\n"
                "  --race-every-lane 1\n"
                "                   race every lane, also on photos those that cannot be chosen (as before session 16)");
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
    else if (a == "--real") real = v;
    else if (a == "--split") split = v;
    else if (a == "--real-images") real_images = v;
    else if (a == "--json") json_out = v;
    else if (a == "--selection-override") override_file = v;
    else if (a == "--threads") threads = std::stoi(v);
    else if (a == "--only") {
      std::stringstream list(v);
      for (std::string item; std::getline(list, item, ',');) only_targets.insert(std::stoi(item));
    }
    else if (a == "--refine-every-finalist") refine_every = v == "1" || v == "yes";
    else if (a == "--polish-every-finalist") polish_every = v == "1" || v == "yes";
    else if (a == "--race-every-lane") race_every = v == "1" || v == "yes";
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (db.empty()) {
    std::fprintf(stderr, "--db CATALOG is required\n");
    return 2;
  }
  if (split != "tune" && split != "report" && split != "all") {
    std::fprintf(stderr, "--split must be tune, report or all\n");
    return 2;
  }
  if (targets < 0) targets = real.empty() ? 53 : 0;
  try {
    const auto& lib = ShaderLibrary::builtin();
    catalog::Store store(db, catalog::Store::Access::Read);
    // As `proctex match` does: a catalogue of older shader sources would be measured silently
    // (in session 19 an older binary started on a newer catalogue without a word).
    catalog::require_current_sources(store, lib);
    std::vector<std::string> names;
    for (const auto& s : store.shaders()) names.push_back(s.name);
    std::sort(names.begin(), names.end());
    if (!only.empty()) {
      std::vector<std::string> keep;
      for (const auto& n : names)
        if (("," + only + ",").find("," + n + ",") != std::string::npos) keep.push_back(n);
      names = keep;
    }
    nlohmann::json overrides = nlohmann::json::object();
    if (!override_file.empty()) overrides = nlohmann::json::parse(std::ifstream(override_file));
    search::MatchOptions options;
    if (evaluations > 0) options.refine.max_evaluations = evaluations;
    if (starts > 0) options.starts = starts;
    if (candidates >= 0) options.candidate_shaders = candidates;
    if (race > 0) options.race = race;
    if (screen_resolution > 0) options.screen_resolution = screen_resolution;
    options.threads = threads;
    options.refine_every_finalist = refine_every;
    options.polish_every_finalist = polish_every;
    options.race_every_lane = race_every;
    if (!pictures.empty()) fs::create_directories(pictures);
    Renderer renderer(lib);

    std::string table =
        "| # | target shader | structural rank | matched | S | ceiling | S/ceiling | reproduced | verdict | time (s) | "
        "renders | param error | discrete exact | params exact | image RMSE |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    std::vector<double> sims, times, param_errors, ranks, ceilings, ratios;
    int identified = 0, det_total = 0, det_exact = 0, det_params_exact = 0, det_params_inert = 0, det_params_equivalent = 0, det_image_exact = 0, good = 0, approximate = 0, reproduced = 0;
    const metrics::Metric& metric = metrics::default_metric();
    nlohmann::json synthetic_rows = nlohmann::json::array();
    std::vector<Image> tiles;
    std::vector<std::string> labels;
    for (int i = 0; i < targets; ++i) {
      const ShaderDecl& decl = lib.get(names[i % names.size()]);
      const ParameterSpace space(decl);
      std::vector<double> unit(space.dimensions());
      Random rng = Random::for_target(seed, decl.name, i);
      for (auto& u : unit) u = rng.unit();
      unit = space.snap(unit);
      const auto packed = space.to_packed(unit);
      const uint32_t render_seed = 7000000u + i;
      if (!only_targets.empty() && !only_targets.count(i + 1)) continue;
      RenderSettings rs;
      const Image target = renderer.render_batch(decl, {packed}, {render_seed}, rs).front();
      // Noise ceiling: the same spec with other render seeds, against the target (mean of 3).
      const auto target_features = metric.features(target, options.resolution);
      std::vector<double> seed_similarities;
      for (const Image& other :
           renderer.render_batch(decl, {packed, packed, packed}, {render_seed + 1000000u, render_seed + 2000000u,
                                                                   render_seed + 3000000u}, rs))
        seed_similarities.push_back(metric.similarity(target_features, metric.features(other, options.resolution)));
      const double ceiling = (seed_similarities[0] + seed_similarities[1] + seed_similarities[2]) / 3.0;
      const auto t0 = std::chrono::steady_clock::now();
      const double cpu0 = process_cpu_seconds();
      const auto r = search::match(target, store, options);
      const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double cpu = process_cpu_seconds() - cpu0;
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
      const double ratio = ceiling > 0 ? r.similarity / ceiling : 0.0;
      const bool repro = hit || r.similarity >= 0.95 * ceiling;
      reproduced += repro;
      ceilings.push_back(ceiling);
      ratios.push_back(ratio);
      good += r.verdict == "good";
      approximate += r.verdict == "approximate";
      sims.push_back(r.similarity);
      times.push_back(secs);
      std::string err = "-", exact = "-", params_exact = "-", image_err = "-";
      if (deterministic(renderer, decl, packed)) {
        ++det_total;
        if (hit) {
          const auto matched_packed = resolve(decl, r.spec);
          const auto matched = space.to_unit(matched_packed);
          // |unit difference| per dimension; a parameter with a declared symmetry period
          // (shader.h `period=`: a star turned by 360/n is the same image) is compared modulo
          // its period at the target's counts, as a fraction of its range (linear by declaration).
          std::vector<double> diff(unit.size());
          for (size_t d = 0; d < unit.size(); ++d) {
            const Dimension& dim = space.dims()[d];
            diff[d] = std::fabs(matched[d] - unit[d]);
            if (dim.param->period > 0.0f && !dim.levels)
              diff[d] = parameter_difference(decl, *dim.param, matched_packed[dim.param->offset],
                                             packed[dim.param->offset], packed) /
                        (dim.param->max - dim.param->min);
          }
          double sum = 0;
          bool all_exact = true;
          for (size_t d = 0; d < unit.size(); ++d) {
            sum += diff[d];
            if (space.dims()[d].levels && diff[d] > 1e-6) all_exact = false;
          }
          const double e = unit.empty() ? 0.0 : sum / unit.size();
          param_errors.push_back(e);
          det_exact += all_exact;
          err = fmt::format("{:.3f}", e);
          exact = all_exact ? "yes" : "no";
          // The criterion: discrete exact and every continuous one within 2% of its range.
          bool within = all_exact;
          for (size_t d = 0; d < unit.size(); ++d)
            if (!space.dims()[d].levels && diff[d] > 0.02) within = false;
          det_params_exact += within;
          params_exact = within ? "yes" : "no";
          // Inert parameters (reported apart, never counted as exact): a continuous parameter more
          // than 2% off whose target value, put into the match, renders bit for bit the match's
          // image - the shader does not use it there (grid: the minor lines' width is clamped at
          // 0.4 of a minor cell, beyond which minor_width changes nothing). No image can tell such
          // values apart; measured by rendering, whatever the shader.
          if (all_exact && !within) {
            const Image as_matched = renderer.render_batch(decl, {matched_packed}, {render_seed}, rs).front();
            std::string inert;
            bool all_inert = true;
            for (size_t d = 0; d < unit.size() && all_inert; ++d) {
              if (space.dims()[d].levels || diff[d] <= 0.02) continue;
              const Dimension& dim = space.dims()[d];
              auto moved = matched_packed;
              moved[dim.param->offset + dim.channel] = packed[dim.param->offset + dim.channel];
              const Image other = renderer.render_batch(decl, {moved}, {render_seed}, rs).front();
              if (other.pixels != as_matched.pixels) all_inert = false;
              else inert += (inert.empty() ? "" : ", ") + dim.param->name;
            }
            if (all_inert) {
              ++det_params_inert;
              params_exact = "no (inert: " + inert + ")";
            }
          }
        } else {
          exact = params_exact = "no";
        }
        // Image: the matched spec (any shader) rendered like the target, 256 px.
        const Image matched_image = renderer.render(r.spec, rs);
        const double rmse = shifted_rmse(target, matched_image);
        det_image_exact += rmse <= kImageExactRmse;
        image_err = fmt::format("{:.4f}", rmse);
        // Equivalent parameters: another point of the same shader that renders the same image
        // where it stands (no shift): a star turned by its own symmetry, a duty's complement in
        // swapped colours about the centre, a grid's minor lines where they are too thin to show.
        const bool equivalent = params_exact == "yes" ||
                                (hit && rmse_at(target, matched_image, 0, 0) <= kImageExactRmse);
        det_params_equivalent += equivalent;
        if (params_exact.find("inert") == std::string::npos)
          params_exact += equivalent && params_exact != "yes" ? " (equivalent)" : "";
      }
      table += fmt::format("| {} | {} | {} | {} | {:.3f} | {:.3f} | {:.2f} | {} | {} | {:.1f} | {} | {} | {} | {} | {} |\n",
                           i + 1, decl.name, rank, r.spec.shader, r.similarity, ceiling, ratio, repro ? "yes" : "no",
                           r.verdict, secs, r.evaluations, err, exact, params_exact, image_err);
      synthetic_rows.push_back({{"target", i + 1}, {"shader", decl.name}, {"matched", r.spec.shader}, {"identified", hit},
                                {"similarity", r.similarity}, {"ceiling", ceiling},
                                {"ceiling_per_seed", seed_similarities}, {"ratio", ratio},
                                {"reproduced", repro}, {"verdict", r.verdict}, {"seconds", secs}, {"cpu_seconds", cpu},
                                {"discrete_exact", exact}, {"params_exact", params_exact}, {"image_rmse", image_err}});
      std::fprintf(stderr, "%2d/%d %-14s (rank %s) -> %-14s S=%.3f ceiling %.3f %-11s %.1f s (CPU %.1f s)\n", i + 1,
                   targets, decl.name.c_str(), rank.c_str(), r.spec.shader.c_str(), r.similarity, ceiling,
                   r.verdict.c_str(), secs, cpu);
      if (!pictures.empty()) {  // the whole result, to see where a miss was lost (scan, screen, race)
        nlohmann::json j = r.to_json();
        j["target"] = {{"spec", spec_from_packed(decl, packed, render_seed).to_json()}, {"seconds", secs}, {"cpu_seconds", cpu},
                       {"ceiling", ceiling}, {"ceiling_per_seed", seed_similarities}, {"reproduced", repro}};
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
    std::string summary = targets <= 0 ? std::string() : fmt::format(
        "Synthetic recovery: {} targets, shader identified {}/{} ({:.0f}%), reproduced (identified or S >= 0.95 x "
        "noise ceiling) {}, median S / ceiling {:.3f}, median ceiling {:.3f}, target shader among the first 1 / 5 / "
        "12 of the structural scan {} / {} / {}, median S {:.3f}, verdicts good {} / "
        "approximate {} / no-match {}; deterministic targets {}: all discrete parameters exact {}, all parameters "
        "exact (discrete exact, continuous within 2% of range) {} (+ {} whose only misses are inert parameters: the target's value renders the match's image bit for bit), or equivalent (the same image unshifted) {}, image exact (RGB RMSE <= {} at the best shift, "
        "on the overlap) {}, "
        "median parameter error {:.3f} (mean |unit difference|, identified ones); time per match median {:.1f} s, "
        "worst {:.1f} s.\n\n",
        targets, identified, targets, 100.0 * identified / std::max(1, targets), percent(reproduced, targets),
        median(ratios), median(ceilings),
        std::count_if(ranks.begin(), ranks.end(), [](double r) { return r <= 1; }),
        std::count_if(ranks.begin(), ranks.end(), [](double r) { return r <= 5; }),
        std::count_if(ranks.begin(), ranks.end(), [](double r) { return r <= 12; }), median(sims), good, approximate,
        targets - good - approximate, det_total, det_exact, det_params_exact, det_params_inert, det_params_equivalent, kImageExactRmse, det_image_exact,
        median(param_errors), median(times), worst);

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
    std::string real_report;
    nlohmann::json real_json;
    if (!real.empty()) {
      nlohmann::json labels;
      if (!fs::is_regular_file(real)) throw Error("labels file " + real + " not found", "give --real bench/realset/labels.json");
      try {
        labels = nlohmann::json::parse(std::ifstream(real));
      } catch (const std::exception& e) {
        throw Error("cannot read the labels " + real + ": " + e.what(), "give --real bench/realset/labels.json");
      }
      if (!labels.contains("images") || !labels["images"].is_array())
        throw Error(real + " has no \"images\" array", "give --real bench/realset/labels.json");
      struct Row {
        std::string id, kind;
        std::vector<std::string> accepted, top3;
        std::string matched, verdict;
        double similarity = 0, seconds = 0, cpu_seconds = 0;
        bool right = false, right3 = false;
      };
      std::vector<Row> rows;
      std::vector<nlohmann::json> items;
      for (const auto& item : labels["images"])
        if (split == "all" || item.value("split", "") == split) items.push_back(item);
      if (items.empty()) throw Error("no images of split " + split + " in " + real, "check --split");
      {  // all present before minutes of matching
        std::vector<std::string> missing;
        for (const auto& item : items)
          if (!fs::exists(fs::path(real_images) / (item.value("id", "") + ".png"))) missing.push_back(item.value("id", ""));
        if (!missing.empty())
          throw Error(fmt::format("{} of the {} images of split {} are missing in {} (first: {}.png)", missing.size(),
                                  items.size(), split, real_images, missing.front()),
                      "build the set first: python3 bench/realset/build.py");
      }
      std::vector<Image> tiles;
      std::vector<std::string> tile_labels;
      const int tile = 256;  // 6 columns: 3 photo | match pairs a row
      for (size_t n = 0; n < items.size(); ++n) {
        const auto& item = items[n];
        Row row;
        row.id = item.at("id").get<std::string>();
        row.kind = item.at("kind").get<std::string>();
        row.accepted = item.at("accepted").get<std::vector<std::string>>();
        const fs::path file = fs::path(real_images) / (row.id + ".png");
        if (!fs::exists(file))
          throw Error(file.string() + " is missing", "build the set first: python3 bench/realset/build.py");
        const Image target = search::prepare_target(file, "");
        search::MatchOptions photo_options = options;
        if (overrides.contains(row.id)) photo_options.selection_override = overrides.at(row.id).get<std::map<std::string, double>>();
        else if (!override_file.empty())
          throw Error(row.id + " has no probabilities in " + override_file, "give every photo of the split");
        const auto t0 = std::chrono::steady_clock::now();
        const double cpu0 = process_cpu_seconds();
        const auto r = search::match(target, store, photo_options);
        row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        row.cpu_seconds = process_cpu_seconds() - cpu0;
        row.matched = r.spec.shader;
        row.similarity = r.similarity;
        row.verdict = r.verdict;
        const std::set<std::string> ok(row.accepted.begin(), row.accepted.end());
        row.right = ok.count(row.matched) > 0;
        const auto ranking = shader_ranking(r);
        for (size_t k = 0; k < ranking.size() && k < 3; ++k) {
          row.top3.push_back(ranking[k]);
          row.right3 |= ok.count(ranking[k]) > 0;
        }
        std::fprintf(stderr, "%2zu/%zu %-40s %-14s -> %-14s S=%.3f %-11s %s %.1f s (CPU %.1f s)\n", n + 1, items.size(),
                     row.id.c_str(), row.kind.c_str(), row.matched.c_str(), row.similarity, row.verdict.c_str(),
                     row.right ? "right" : (row.right3 ? "top-3" : "WRONG"), row.seconds, row.cpu_seconds);
        if (!pictures.empty()) {
          nlohmann::json j = r.to_json();
          j["label"] = item;
          j["evaluation"] = {{"right", row.right}, {"top3", row.top3}, {"right_top3", row.right3},
                             {"ranking", ranking}, {"seconds", row.seconds}, {"cpu_seconds", row.cpu_seconds}};
          std::ofstream(fs::path(pictures) / (row.id + ".json")) << j.dump(1) << "\n";
          RenderSettings rs;
          rs.width = rs.height = 256;
          const Image photo_tile = side_by_side_tile(target, 256);
          const Image m = renderer.render(r.spec, rs);
          const std::string verdict_text = fmt::format("{} S={:.2f} {} {}", row.matched, row.similarity, row.verdict,
                                                       row.right ? "(right)" : "(WRONG)");
          save_image(contact_sheet({photo_tile, m}, {row.id, verdict_text}, 2, 256), fs::path(pictures) / (row.id + ".jpg"));
          tiles.push_back(resize(photo_tile, tile, tile));
          tile_labels.push_back(row.id);
          tiles.push_back(resize(m, tile, tile));
          tile_labels.push_back(fmt::format("{} {} {:.2f} {}", row.right ? "ok" : "X", row.matched, row.similarity,
                                            row.verdict == "approximate" ? "approx" : row.verdict));
        }
        rows.push_back(std::move(row));
      }
      if (!pictures.empty() && !tiles.empty())
        save_image(contact_sheet(tiles, tile_labels, 6, tile), fs::path(pictures) / ("real-" + split + ".jpg"));

      const int total = static_cast<int>(rows.size());
      int right = 0, right3 = 0, wrong_good = 0, good_total = 0, good_right = 0, approx = 0;
      std::vector<double> secs, cpu_secs;
      std::map<std::string, std::array<int, 3>> per_kind;  // n, right, top-3
      for (const auto& row : rows) {
        right += row.right;
        right3 += row.right3;
        good_total += row.verdict == "good";
        good_right += row.verdict == "good" && row.right;
        wrong_good += row.verdict == "good" && !row.right;
        approx += row.verdict == "approximate";
        secs.push_back(row.seconds);
        cpu_secs.push_back(row.cpu_seconds);
        auto& k = per_kind[row.kind];
        k[0]++;
        k[1] += row.right;
        k[2] += row.right3;
      }
      real_report = fmt::format(
          "Real set ({}, split {}): {} images; category accuracy {}, top-3 accuracy {}, wrong-category results "
          "called good {} of the wrong ones, precision of good (right kind among good) {}; verdicts good {} / "
          "approximate {} / no-match {}; time per match median {:.1f} s (CPU {:.1f} s).\n\n",
          real, split, total, percent(right, total), percent(right3, total), percent(wrong_good, total - right),
          percent(good_right, good_total), good_total, approx, total - good_total - approx, median(secs), median(cpu_secs));
      real_report += "| kind | images | right | top-3 |\n|---|---|---|---|\n";
      for (const auto& [kind, k] : per_kind) real_report += fmt::format("| {} | {} | {} | {} |\n", kind, k[0], k[1], k[2]);
      real_report +=
          "\n| image | kind | accepted | matched | S | verdict | right? | top-3 | time (s) |\n"
          "|---|---|---|---|---|---|---|---|---|\n";
      nlohmann::json jrows = nlohmann::json::array();
      for (const auto& row : rows) {
        real_report += fmt::format("| {} | {} | {} | {} | {:.3f} | {} | {} | {} | {:.1f} |\n", row.id, row.kind,
                                   join(row.accepted), row.matched, row.similarity, row.verdict,
                                   row.right ? "yes" : (row.right3 ? "no (top-3)" : "no"), join(row.top3), row.seconds);
        jrows.push_back({{"id", row.id}, {"kind", row.kind}, {"accepted", row.accepted}, {"matched", row.matched},
                         {"similarity", row.similarity}, {"verdict", row.verdict}, {"right", row.right},
                         {"top3", row.top3}, {"right_top3", row.right3}, {"seconds", row.seconds},
                         {"cpu_seconds", row.cpu_seconds}});
      }
      real_json = {{"labels", real},
                   {"split", split},
                   {"images", total},
                   {"category_accuracy", total ? double(right) / total : 0.0},
                   {"top3_accuracy", total ? double(right3) / total : 0.0},
                   {"wrong_good_share", total - right ? double(wrong_good) / (total - right) : 0.0},
                   {"good_precision", good_total ? double(good_right) / good_total : 0.0},
                   {"right", right},
                   {"right_top3", right3},
                   {"wrong_good", wrong_good},
                   {"good", good_total},
                   {"median_seconds", median(secs)},
                   {"median_cpu_seconds", median(cpu_secs)},
                   {"rows", jrows}};
    }

    const std::string report =
        summary + (targets > 0 ? table + "\n" : std::string()) + photo_table + (photo_table.empty() ? "" : "\n") + real_report;
    std::fputs(report.c_str(), stdout);
    if (!markdown.empty()) std::ofstream(markdown) << report;
    if (!json_out.empty()) {
      nlohmann::json j = {{"catalogue", db}};
      if (targets > 0)
        j["synthetic"] = {{"targets", targets},       {"identified", identified},       {"reproduced", reproduced},
                          {"median_ratio", median(ratios)}, {"median_ceiling", median(ceilings)},
                          {"median_similarity", median(sims)}, {"deterministic", det_total},
                          {"discrete_exact", det_exact}, {"params_exact", det_params_exact}, {"params_inert", det_params_inert},
                          {"params_equivalent", det_params_equivalent}, {"image_exact", det_image_exact},
                          {"rows", synthetic_rows}};
      if (!real_json.is_null()) j["real"] = real_json;
      const fs::path tmp = json_out + ".tmp";
      std::ofstream(tmp) << j.dump(1) << "\n";
      fs::rename(tmp, json_out);
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "bench_match_eval: %s (%s)\n", e.message().c_str(), e.hint().c_str());
    return 1;
  }
  return 0;
}
