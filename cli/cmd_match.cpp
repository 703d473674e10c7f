// proctex match PHOTO: the shader and parameters that reproduce a photo.
#include <cmath>
#include <csignal>
#include <filesystem>
#include <sstream>

#include <fmt/format.h>

#include "catalog/catalog.h"
#include "catalog/store.h"
#include "cli/commands.h"
#include "cli/match_batch.h"
#include "cli/output.h"
#include "core/error.h"
#include "search/match.h"
#include "shaders/renderer.h"

namespace proctex::cli {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_interrupt(int) { g_interrupted = true; }

// The search defaults come from search::MatchOptions, so the CLI and the API cannot drift apart.
struct MatchCliOptions {
  std::string photo;
  std::string db;
  std::string crop;
  std::string shaders;
  std::string optimizer = search::to_string(search::MatchOptions{}.refine.optimizer);
  std::string budget;
  std::vector<std::string> fix;
  std::string output;
  std::string render;
  std::string compare;
  int size = 1024;
  int candidates = search::MatchOptions{}.candidate_shaders;
  int screen_resolution = search::MatchOptions{}.screen_resolution;
  double threshold = 0.0;
  int screen = search::MatchOptions{}.screen;
  int race = search::MatchOptions{}.race;
  int starts = search::MatchOptions{}.starts;
  long max_evaluations = search::MatchOptions{}.refine.max_evaluations;
  bool json = false;
  MatchBatchCli batch;  // a folder or list of photos (cli/match_batch.h)
};

// A similarity as printed next to its verdict: rounded down, so 0.4996 reads 0.499 beside
// "approximate" instead of 0.500 (the "good" threshold).
double shown(double similarity, int digits) {
  const double scale = std::pow(10.0, digits);
  return std::floor(similarity * scale) / scale;
}

// "approximate" only because a clean pattern is close without the spectrum (search/match.h verdict_for).
bool approximate_by_pattern(const search::MatchResult& r) {
  return r.verdict == "approximate" && r.similarity < search::kApproximateMatch;
}

// What the user can do next, by verdict: the summary's last line.
std::string next_step(const search::MatchResult& r, const std::string& photo) {
  std::string others;
  int n = 0;
  for (const auto& c : r.candidates)
    if (c.shader != r.spec.shader && n < 3) others += (n++ ? "," : "") + c.shader;
  if (r.pixel_exact)
    return fmt::format("next: the pattern is reproduced pixel for pixel (RGB RMS difference {:.4f}, up to where it "
                       "starts); render it at any size: proctex render SPEC.json -o big.png --size 4096",
                       r.image_rmse);
  if (r.verdict == "good")
    return fmt::format("next: render it at any size: proctex render SPEC.json -o big.png --size 4096 "
                       "(the material is {:.0f}% likely by the selection)", 100 * r.probability);
  if (approximate_by_pattern(r))
    return fmt::format("next: {} draws the same kind of pattern with its details off (compare with --compare side.png); "
                       "pin what you can read off the photo with --fix name=value (proctex shaders show {}) and match again",
                       r.spec.shader, r.spec.shader);
  if (r.verdict == "approximate")
    return fmt::format("next: {} ({} at {:.0f}% by the selection, which calls a photo good only at {:.0f}%); compare "
                       "with --compare side.png, try the other likely materials with --shaders {}, or crop a clean "
                       "region with --crop x,y,w,h",
                       r.similarity < search::kGoodMatch ? "not as similar as another crop of one texture would be"
                                                         : "similar, but the material is not certain enough",
                       r.spec.shader, 100 * r.probability, 100 * search::kGoodProbability,
                       others.empty() ? r.spec.shader : others);
  return "next: no shader of the library reproduces " + photo +
         "; synthesise more of it from the photo itself (exemplar synthesis), or crop a region with one material";
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, sep))
    if (!item.empty()) out.push_back(item);
  return out;
}

// "30s", "2m" (seconds) or "500" (evaluations).
search::Budget parse_budget(const std::string& text) {
  search::Budget b;
  if (text.empty()) return b;
  try {
    size_t used = 0;
    const double v = std::stod(text, &used);
    const std::string unit = text.substr(used);
    if (v <= 0) throw std::invalid_argument(text);
    if (unit == "s") b.max_seconds = v;
    else if (unit == "m") b.max_seconds = 60 * v;
    else if (unit.empty() || unit == "e") b.max_evaluations = static_cast<long>(v);
    else throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw UsageError("--budget '" + text + "' is not a time (30s, 2m) or an evaluation count (500)",
                     "write --budget 20s or --budget 400");
  }
  return b;
}

std::map<std::string, nlohmann::json> parse_fixed(const std::vector<std::string>& items) {
  std::map<std::string, nlohmann::json> out;
  for (const auto& item : items) {
    // Reuse the inline-spec parser for the value syntax (numbers, enums, colours).
    const TextureSpec s = parse_spec_argument("x:" + item);
    if (s.params.empty()) throw UsageError("--fix '" + item + "' is not name=value", "write --fix rows=8");
    for (const auto& [k, v] : s.params) out[k] = v;
  }
  return out;
}

void write_compare(const std::string& path, const Image& target, const Image& match, const search::MatchResult& r) {
  const int side = std::min(512, std::max(match.width, 256));
  const Image t = resize(center_crop_square(target), side, side);
  const Image m = resize(match, side, side);
  save_image(contact_sheet({t, m}, {"target", fmt::format("{} S={:.2f} ({})", r.spec.shader, shown(r.similarity, 2), r.verdict)}, 2, side),
             path);
}

void run(const MatchCliOptions& o, const GlobalOptions& global) {
  search::MatchOptions options;
  options.shaders = split(o.shaders, ',');
  options.candidate_shaders = o.candidates;
  options.shader_threshold = o.threshold;
  options.screen = o.screen;
  options.screen_resolution = o.screen_resolution;
  options.race = o.race;
  options.starts = o.starts;
  options.refine.optimizer = search::parse_optimizer(o.optimizer);
  options.refine.max_evaluations = o.max_evaluations;
  options.budget = parse_budget(o.budget);
  options.fixed = parse_fixed(o.fix);
  if (is_match_batch(o.photo, o.batch)) return run_match_batch(o.photo, o.crop, o.db, options, o.batch, o.json, global);

  const Image target = search::prepare_target(o.photo, o.crop);
  const std::filesystem::path db = o.db.empty() ? catalog::default_catalog_path() : std::filesystem::path(o.db);
  if (!std::filesystem::exists(db))
    throw Error("no catalogue at '" + db.string() + "'", "build one: proctex catalog build --db " + db.string());
  catalog::Store store(db, catalog::Store::Access::Read);
  catalog::require_current_sources(store);

  g_interrupted = false;
  auto previous = std::signal(SIGINT, on_interrupt);
  Progress progress("match", 0, global.quiet);
  const auto result = search::match(target, store, options, [&](const search::MatchProgress& p) {
    progress.update(0, fmt::format("{}  best {:.3f} {}  {} renders", p.stage, p.best, p.best_shader, p.evaluations));
  }, &g_interrupted);
  progress.finish();
  std::signal(SIGINT, previous);

  nlohmann::json j = result.to_json();
  j["target"] = {{"path", o.photo}, {"width", target.width}, {"height", target.height}, {"crop", o.crop}};
  if (!o.output.empty()) write_text_file(o.output, j.dump(2) + "\n");
  if (!o.render.empty() || !o.compare.empty()) {
    Renderer renderer;
    RenderSettings settings;
    settings.width = settings.height = o.size;
    const Image img = renderer.render(result.spec, settings);
    if (!o.render.empty()) save_image(img, o.render);
    if (!o.compare.empty()) write_compare(o.compare, target, img, result);
  }
  if (o.json) return print_json(j);
  if (result.pixel_exact)
    std::printf("%s: %s (%s: pixel-exact, RGB RMS difference %.4f; statistical similarity %.3f)\n", o.photo.c_str(),
                result.spec.shader.c_str(), result.verdict.c_str(), result.image_rmse, shown(result.similarity, 3));
  else if (approximate_by_pattern(result))
    std::printf("%s: %s (similarity %.3f, %s: the same kind of pattern, %.3f without the spectrum, whose peaks "
                "sit elsewhere)\n",
                o.photo.c_str(), result.spec.shader.c_str(), shown(result.similarity, 3), result.verdict.c_str(),
                shown(result.pattern_similarity, 3));
  else
    std::printf("%s: %s (similarity %.3f, %s)\n", o.photo.c_str(), result.spec.shader.c_str(),
                shown(result.similarity, 3), result.verdict.c_str());
  std::printf("spec: %s\n", result.spec.to_json().dump().c_str());
  std::string parts;
  for (const auto& [k, v] : result.per_metric) parts += fmt::format("{}{} {:.3f}", parts.empty() ? "" : ", ", k, v);
  std::printf("metrics: %s\n", parts.c_str());
  std::printf("%ld renders in %s%s\n", result.evaluations, format_seconds(result.timings["total"].get<double>()).c_str(),
              result.stopped_early ? " (stopped early: best so far)" : "");
  for (const auto* path : {&o.output, &o.render, &o.compare})
    if (!path->empty()) std::printf("wrote %s\n", path->c_str());
  std::printf("%s\n", next_step(result, o.photo).c_str());
}

}  // namespace

void add_match_command(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<MatchCliOptions>();
  auto* cmd = app.add_subcommand("match", "Find the shader and parameters that reproduce a photo");
  cmd->footer(
      "Decides which materials the photo is likely to be (a classifier over its statistics at several\n"
      "scales, plus the nearest catalogue samples), fits the colours of the best samples of the likely\n"
      "shaders, refines the best starts with NLopt (and polishes clean patterns exactly), and keeps the\n"
      "result that is both similar and a likely material.\n"
      "Verdict: good (similarity >= 0.5 and the material at least 95% likely, or similarity >= 0.75),\n"
      "approximate (>= 0.25; on a clean pattern also >= 0.25 without the spectrum, which rates a pattern\n"
      "whose peaks sit a few frequency bins off as unrelated), no-match (no shader expresses the photo).\n"
      "See docs/search.md.\n"
      "  proctex match brick.png --render match.png --size 4096 --compare cmp.png\n"
      "  proctex match wall.jpg --shaders bricks,tiles --fix rows=8 --budget 20s -o result.json\n"
      "Ctrl-C stops the search and returns the best match so far.");
  cmd->add_option("photo", o->photo, "Target image (PNG, JPEG, TIFF, EXR)")->required();
  cmd->add_option("--db", o->db, "Catalogue (default: $PROCTEX_CATALOG or ~/.cache/proctex/catalog.sqlite)");
  cmd->add_option("--crop", o->crop, "Use only this part of the photo: x,y,w,h (default: the whole photo, centre square)");
  cmd->add_option("--shaders", o->shaders, "Only these shaders, comma-separated (your knowledge of the material)");
  cmd->add_option("--candidates", o->candidates, "Shaders screened: the M most likely materials by the shader selection (0: all, slower)")->capture_default_str()->check(CLI::Range(0, 100000));
  cmd->add_option("--screen", o->screen, "Best catalogue samples per shader whose colours are fitted and scored")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--screen-resolution", o->screen_resolution, "Resolution of the screening renders (smaller is faster but loses thin structure)")->capture_default_str()->check(CLI::Range(64, 1024));
  cmd->add_option("--threshold", o->threshold, "Also screen every shader whose selection probability (the evidence for its material) reaches this")->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--race", o->race, "Starting points given a short refinement (on a photo, those whose material is too unlikely\n"
                  "to be chosen even at a perfect similarity are left out: JSON \"raced\": false)")->capture_default_str()->check(CLI::Range(1, 256));
  cmd->add_option("--starts", o->starts, "Best of those refined to the end")->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--optimizer", o->optimizer, "neldermead, subplex, bobyqa, global or gradient")->capture_default_str();
  cmd->add_option("--evaluations", o->max_evaluations, "Renders per starting point refined to the end (race lanes get 1/5). 200 is a quarter faster on photos, the same\n"
                  "materials on the labelled set, but fewer patterns recovered exactly (docs/performance.md, session 15)")->capture_default_str()->check(CLI::Range(1L, 1000000L));
  cmd->add_option("--budget", o->budget, "Stop after this time (20s, 2m) or this many renders (500), with the best so far");
  cmd->add_option("--fix", o->fix, "Pin a parameter: name=value (repeatable)");
  cmd->add_option("-o,--output", o->output, "Write the match result JSON here");
  cmd->add_option("--render", o->render, "Render the match to this image");
  cmd->add_option("--size", o->size, "Size of --render and --compare images")->capture_default_str()->check(CLI::Range(16, 65536));
  cmd->add_option("--compare", o->compare, "Write target and match side by side");
  cmd->add_flag("--json", o->json, "Print the match result as JSON");
  add_match_batch_options(*cmd, o->batch);
  cmd->callback([o, &global] { run(*o, global); });
}

}  // namespace proctex::cli
