// proctex synth EXEMPLAR -o out.png: exemplar-based texture synthesis (synth/).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <sstream>

#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "kernels/runtime.h"
#include "synth/analysis.h"
#include "synth/graph_synthesis.h"
#include "synth/render.h"
#include "synth/synthesis.h"
#include "synth/timing.h"

namespace proctex::cli {
namespace {

struct SynthCliOptions {
  std::string exemplar;
  std::string output;
  std::string size = "512";
  std::string window;
  int64_t seed = 1;
  std::string randomness = "1,0";
  std::string passes = "0,0,2";
  // -1 = the default: 32 for one exemplar (issue 13, fifth pass: with the 4 px seam blend, bench
  // median coherence 5.14 -> 5.04), 8 - the library's, kept by rgbn and the service - with --graph.
  float kappa = -1.0f;
  int finest_passes = synth::SynthOptions{}.finest_passes;
  int refine_passes = synth::SynthOptions{}.refine_passes;
  int rematch_passes = synth::SynthOptions{}.rematch_passes;
  int rematch_candidate_passes = synth::SynthOptions{}.rematch_candidate_passes;
  int layout_shifts = synth::SynthOptions{}.layout_shifts;
  float break_pieces = synth::SynthOptions{}.break_pieces;
  float layout_min_correlation = synth::SynthOptions{}.layout_min_correlation;
  bool tileable = false;
  std::string blend_seams = "on";
  std::string exemplar_tiles = "auto";
  int candidates = 2;
  std::string coords;
  std::string jitter_map;
  std::vector<std::string> pastes;
  std::vector<std::string> apply;
  float map_weight = 0.5f;
  int bits = 0;
  int png_compression = 1;  // --png-compression: deflate level of PNG outputs
  std::string cache_dir;
  bool no_cache = false;
  bool json = false;
  std::string graph;  // --graph g.json: a multiscale exemplar graph instead of one exemplar
  int zoom = 0;
};

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, sep);) out.push_back(item);
  if (!s.empty() && s.back() == sep) out.emplace_back();
  return out;
}

int64_t parse_int(const std::string& text, const std::string& what) {
  try {
    size_t used = 0;
    const long long v = std::stoll(text, &used);
    if (used != text.size()) throw std::invalid_argument(text);
    return v;
  } catch (const std::exception&) {
    throw UsageError(fmt::format("{}: '{}' is not an integer", what, text));
  }
}

void parse_size(const std::string& text, int& w, int& h) {
  const auto x = text.find_first_of("xX");
  const std::string a = x == std::string::npos ? text : text.substr(0, x);
  const std::string b = x == std::string::npos ? text : text.substr(x + 1);
  const int64_t W = parse_int(a, "--size"), H = parse_int(b, "--size");
  if (W < 1 || H < 1 || W > 65536 || H > 65536)
    throw UsageError(fmt::format("--size {} is out of range", text), "use WxH or N with 1..65536 pixels per side");
  w = static_cast<int>(W), h = static_cast<int>(H);
}

synth::Window parse_window(const std::string& text) {
  const auto parts = split(text, ',');
  if (parts.size() != 4)
    throw UsageError(fmt::format("--window '{}' must be x,y,w,h", text), "e.g. --window -512,1024,256,256");
  synth::Window w;
  w.x = parse_int(parts[0], "--window x");
  w.y = parse_int(parts[1], "--window y");
  const int64_t W = parse_int(parts[2], "--window width"), H = parse_int(parts[3], "--window height");
  if (W < 1 || H < 1 || W > 65536 || H > 65536)
    throw UsageError(fmt::format("--window size {}x{} is out of range", W, H), "width and height in 1..65536");
  w.width = static_cast<int>(W), w.height = static_cast<int>(H);
  return w;
}

std::vector<float> parse_randomness(const std::string& text) {
  std::vector<float> out;
  for (const auto& p : split(text, ',')) {
    try {
      size_t used = 0;
      const float v = std::stof(p, &used);
      if (used != p.size()) throw std::invalid_argument(p);
      out.push_back(v);
    } catch (const std::exception&) {
      throw UsageError(fmt::format("--randomness: '{}' is not a number", p), "e.g. 0.5 or 1,1,0.5,0.3,0.2");
    }
  }
  return out;
}

std::vector<int> parse_passes(const std::string& text) {
  std::vector<int> out;
  for (const auto& p : split(text, ',')) {
    try {
      size_t used = 0;
      const int v = std::stoi(p, &used);
      if (used != p.size()) throw std::invalid_argument(p);
      out.push_back(v);
    } catch (const std::exception&) {
      throw UsageError(fmt::format("--passes: '{}' is not a whole number", p), "e.g. 2 or 4,4,2,2,1");
    }
  }
  return out;
}

// proctex synth --graph g.json: synthesis on a multiscale exemplar graph (synth/graph_synthesis.h).
void run_graph(const SynthCliOptions& o, const GlobalOptions& global) {
  using namespace synth;
  if (!o.exemplar.empty())
    throw UsageError(fmt::format("give either an exemplar ('{}') or --graph, not both", o.exemplar),
                     "the graph file lists its exemplars");
  if (o.tileable || !o.jitter_map.empty() || !o.pastes.empty() || !o.apply.empty() || o.exemplar_tiles != "auto" ||
      o.candidates != 2)
    throw UsageError("--tileable, --jitter-map, --paste, --apply, --exemplar-tiles and --candidates are not available with --graph",
                     "set \"tiles\" per exemplar in the graph file");
  int width = 0, height = 0;
  parse_size(o.size, width, height);
  Window window{0, 0, width, height};
  if (!o.window.empty()) window = parse_window(o.window);
  check_dimensions(window.width, window.height);
  if (o.zoom < 0 || o.zoom > kMaxGraphZoom)
    throw UsageError(fmt::format("--zoom {} is out of range", o.zoom), fmt::format("use 0..{}", kMaxGraphZoom));
  SynthOptions options;
  options.seed = static_cast<uint32_t>(o.seed);
  options.randomness = parse_randomness(o.randomness);
  options.passes = parse_passes(o.passes);
  options.finest_passes = o.finest_passes;
  options.kappa = o.kappa >= 0 ? o.kappa : synth::SynthOptions{}.kappa;
  std::vector<StripTarget> files{{o.output, false}};
  if (!o.coords.empty()) files.push_back({o.coords, true});
  RenderOutputs check;
  check.colour = o.output;
  check.coords = o.coords;
  check.bits = o.bits;
  check_outputs(check, Exemplar{});

  const LoadedGraph graph = load_graph(std::filesystem::path(o.graph));
  const LevelSchedule schedule = level_schedule(graph.graph, graph_levels(graph), o.zoom);  // zoom check first
  (void)schedule;
  Progress analysing("analysing the graph", 1, global.quiet || o.json);
  const std::filesystem::path cache = o.no_cache ? std::filesystem::path()
                                      : !o.cache_dir.empty() ? std::filesystem::path(o.cache_dir)
                                                             : default_cache_dir();
  const GraphAnalysis analysis = analyse_graph_cached(graph, cache);
  analysing.finish();
  GraphSynthesizer synth(graph, analysis);
  Progress progress("synthesising", 100, global.quiet || o.json);
  // Strips of at most 4 M pixels (the single-exemplar renderer's bound).
  const int rows = static_cast<int>(std::clamp<int64_t>((int64_t(1) << 22) / window.width, 1, window.height));
  std::vector<int64_t> per_exemplar(graph.images.size(), 0);
  const RenderStats stats = write_strips(
      files, window.width, window.height, o.bits, rows,
      [&](int y0, int n, std::vector<std::vector<float>>& data) {
        const Window strip{window.x, window.y + y0, window.width, n};
        const auto px = synth.synthesise(strip, options, o.zoom);
        data[0] = synth.colours(px);
        for (const auto& p : px) ++per_exemplar[p.exemplar];
        if (files.size() > 1)
          for (size_t i = 0; i < px.size(); ++i) {
            data[1][3 * i] = static_cast<float>(px[i].x);
            data[1][3 * i + 1] = static_cast<float>(px[i].y);
            data[1][3 * i + 2] = static_cast<float>(px[i].exemplar);
          }
      },
      [&](double f) { progress.update(static_cast<long>(f * 100)); });
  progress.finish();
  const int mz = max_zoom(graph.graph, analysis.levels);
  if (o.json) {
    nlohmann::json ex = nlohmann::json::array();
    for (size_t i = 0; i < graph.images.size(); ++i)
      ex.push_back({{"image", graph.graph.exemplars[i].image.string()},
                    {"tiles", graph.toroidal[i] != 0},
                    {"pixels", per_exemplar[i]}});
    nlohmann::json edges = nlohmann::json::array();
    for (const auto& e : graph.graph.edges) edges.push_back({{"from", e.from}, {"to", e.to}, {"scale", 1 << e.r}});
    print_json({{"output", o.output},
                {"graph", o.graph},
                {"exemplars", ex},
                {"edges", edges},
                {"exemplar_size", {analysis.width, analysis.height}},
                {"zoom", o.zoom},
                {"max_zoom", mz < 0 ? nlohmann::json("unbounded") : nlohmann::json(mz)},
                {"levels", analysis.levels + o.zoom},
                {"window", {window.x, window.y, window.width, window.height}},
                {"seed", options.seed},
                {"randomness", options.randomness},
                {"passes", options.passes},
                {"finest_passes", options.finest_passes},
                {"coherence", options.kappa},
                {"coords", o.coords},
                {"analysis_hash", analysis.hash},
                {"analysis_cached", analysis.from_cache},
                {"analysis_seconds", analysis.seconds},
                {"synthesis_seconds", stats.seconds},
                {"strips", stats.strips},
                {"device", ocl::Runtime::instance().device().name}});
  } else if (!global.quiet) {
    std::printf("%s: %dx%d at (%lld, %lld), zoom %d, from the %zu-exemplar graph %s (%dx%d) seed %u in %s "
                "(analysis %s)\n",
                o.output.c_str(), window.width, window.height, static_cast<long long>(window.x),
                static_cast<long long>(window.y), o.zoom, graph.images.size(), o.graph.c_str(), analysis.width,
                analysis.height, options.seed, format_seconds(stats.seconds).c_str(),
                analysis.from_cache ? "cached" : format_seconds(analysis.seconds).c_str());
  }
}

void run(const SynthCliOptions& o, const GlobalOptions& global) {
  using namespace synth;
  if (!o.graph.empty()) return run_graph(o, global);
  if (o.exemplar.empty()) throw UsageError("an exemplar image is required", "proctex synth EXEMPLAR -o out.png (or --graph g.json)");
  if (o.zoom != 0) throw UsageError("--zoom needs --graph", "a single exemplar has no finer detail than its own pixels");
  // Parse and check everything before reading pixels or writing files.
  int width = 0, height = 0;
  parse_size(o.size, width, height);
  Window window{0, 0, width, height};
  if (!o.window.empty()) window = parse_window(o.window);
  check_dimensions(window.width, window.height);
  SynthOptions options;
  options.seed = static_cast<uint32_t>(o.seed);
  options.randomness = parse_randomness(o.randomness);
  options.passes = parse_passes(o.passes);
  options.finest_passes = o.finest_passes;
  options.refine_passes = o.refine_passes;
  options.rematch_passes = o.rematch_passes;
  options.rematch_candidate_passes = o.rematch_candidate_passes;
  options.layout_shifts = o.layout_shifts;
  options.break_pieces = o.break_pieces;
  options.layout_min_correlation = o.layout_min_correlation;
  options.kappa = o.kappa >= 0 ? o.kappa : synth::kSingleExemplarCoherence;
  if (o.tileable) {
    options.period_x = width;
    options.period_y = height;
  }
  AnalysisOptions aopt;
  aopt.candidates = o.candidates;
  if (o.exemplar_tiles == "yes") aopt.tiling = Tiling::Toroidal;
  else if (o.exemplar_tiles == "no") aopt.tiling = Tiling::Bounded;
  else if (o.exemplar_tiles != "auto")
    throw UsageError(fmt::format("--exemplar-tiles '{}' must be auto, yes or no", o.exemplar_tiles));

  for (const auto& text : o.pastes) {
    const auto at = text.find('@');
    const auto rect = split(text.substr(0, at), ',');
    const auto pos = at == std::string::npos ? std::vector<std::string>{} : split(text.substr(at + 1), ',');
    if (rect.size() != 4 || pos.size() != 2)
      throw UsageError(fmt::format("--paste '{}' must be EX_X,EX_Y,W,H@X,Y", text),
                       "e.g. --paste 10,20,40,30@300,200 copies the exemplar's 40x30 rectangle at (10,20) to (300,200)");
    SynthOptions::Paste p;
    p.ex_x = static_cast<int>(parse_int(rect[0], "--paste"));
    p.ex_y = static_cast<int>(parse_int(rect[1], "--paste"));
    p.width = static_cast<int>(parse_int(rect[2], "--paste"));
    p.height = static_cast<int>(parse_int(rect[3], "--paste"));
    p.out_x = parse_int(pos[0], "--paste");
    p.out_y = parse_int(pos[1], "--paste");
    options.pastes.push_back(p);
  }
  if (!o.jitter_map.empty()) {
    const Image map = load_image(o.jitter_map);
    options.jitter_map_width = map.width;
    options.jitter_map_height = map.height;
    options.jitter_map.resize(static_cast<size_t>(map.width) * map.height);
    for (size_t i = 0; i < options.jitter_map.size(); ++i) {
      const float* p = map.pixels.data() + 3 * i;
      const float g = linear_to_srgb(std::clamp((p[0] + p[1] + p[2]) / 3.0f, 0.0f, 1.0f));
      options.jitter_map[i] = static_cast<uint8_t>(std::lround(g * 255.0f));
    }
  }
  Exemplar ex;
  ex.name = std::filesystem::path(o.exemplar).filename().string();
  ex.map_weight = o.map_weight;
  RenderOutputs outputs;
  outputs.colour = o.output;
  outputs.coords = o.coords;
  outputs.bits = o.bits;
  outputs.png_compression = o.png_compression;
  if (o.blend_seams == "off") {
    outputs.blend_seams = false;
  } else if (o.blend_seams != "on") {
    const std::string& b = o.blend_seams;
    if (b.size() != 1 || b[0] < '1' || b[0] > '4')
      throw UsageError(fmt::format("--blend-seams '{}' must be on, off or a width of 1..4 pixels", b),
                       "e.g. --blend-seams 3 ramps across each join over 3 pixels on either side");
    outputs.blend_seams = true;
    outputs.blend_radius = b[0] - '0';
  } else {
    outputs.blend_seams = true;
    outputs.blend_radius = synth::kSingleExemplarBlendRadius;  // "on": the command's default width
  }
  struct MapArg {
    std::string kind, in, out;
  };
  std::vector<MapArg> map_args;
  for (const auto& a : o.apply) {
    MapArg m;
    std::string rest = a;
    if (const auto eq = rest.find('='); eq != std::string::npos) m.kind = rest.substr(0, eq), rest = rest.substr(eq + 1);
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == rest.size())
      throw UsageError(fmt::format("--apply '{}' must be [KIND=]IN:OUT", a), "e.g. --apply normal=rock_n.png:out_n.png");
    m.in = rest.substr(0, colon);
    m.out = rest.substr(colon + 1);
    map_args.push_back(m);
    outputs.maps.emplace_back(m.out);
  }
  for (const auto& m : map_args) {
    ExemplarMap em;
    em.name = std::filesystem::path(m.in).filename().string();
    em.kind = parse_map_kind(m.kind, m.in);
    ex.maps.push_back(std::move(em));
  }
  check_outputs(outputs, ex);

  // PoCL's start-up (OpenCL platform, context, program from the binary cache) on a second thread
  // while the exemplar and the cached analysis are read. Nothing may be printed on stderr until it
  // is waited for (see warm_up()). An error there is left for the Synthesizer to raise again; the
  // future's destructor joins the thread on every path, errors included (before main() prints).
  auto warm = std::async(std::launch::async, [] {
    try {
      warm_up();
    } catch (...) {
    }
  });
  timing::mark("start-up, options");
  ex.colour = load_exemplar_image(o.exemplar);
  for (size_t i = 0; i < map_args.size(); ++i) ex.maps[i].image = load_exemplar_image(map_args[i].in);
  validate(ex);
  timing::mark("exemplar read");

  const std::filesystem::path cache = o.no_cache ? std::filesystem::path()
                                      : !o.cache_dir.empty() ? std::filesystem::path(o.cache_dir)
                                                             : default_cache_dir();
  const Analysis analysis = analyse_cached(ex, aopt, cache);
  timing::mark(analysis.from_cache ? "analysis cache load (+ shifts, texels)" : "analysis (not cached)");
  warm.wait();
  check_options(analysis, options);
  if (o.tileable && first_level(analysis, options) > 1 && !global.quiet && !o.json) {
    std::fprintf(stderr,
                 "proctex: note: the period %dx%d is divisible by few powers of two: the coarsest %d levels "
                 "are not randomised (a multiple of %d keeps them all)\n",
                 width, height, first_level(analysis, options) - 1, 1 << (analysis.levels - 1));
  }
  Synthesizer synth(analysis);
  Progress progress("synthesising", 100, global.quiet || o.json);
  const RenderStats stats =
      render(synth, ex, window, options, outputs, [&](double f) { progress.update(static_cast<long>(f * 100)); });
  progress.finish();

  if (o.json) {
    nlohmann::json maps = nlohmann::json::array();
    for (const auto& m : map_args) maps.push_back({{"input", m.in}, {"output", m.out}});
    print_json({{"output", o.output},
                {"exemplar", o.exemplar},
                {"exemplar_size", {analysis.width, analysis.height}},
                {"exemplar_tiles", analysis.toroidal},
                {"candidates", analysis.candidates},
                {"window", {window.x, window.y, window.width, window.height}},
                {"seed", options.seed},
                {"randomness", options.randomness},
                {"passes", options.passes},
                {"finest_passes", options.finest_passes},
                {"refine_seams", options.refine_passes},
                {"rematch", options.rematch_passes},
                {"rematch_candidates", options.rematch_candidate_passes},
                {"layout_shifts", options.layout_shifts},
                {"break_pieces", options.break_pieces},
                {"layout_min_correlation", options.layout_min_correlation},
                {"layout_shifts_used", layout_shift_count(analysis, options)},
                {"coherence", options.kappa},
                {"levels", analysis.levels},
                {"tileable", o.tileable},
                {"blend_seams", outputs.blend_seams},
                {"blend_radius", outputs.blend_seams ? outputs.blend_radius : 0},
                {"coords", o.coords},
                {"jitter_map", o.jitter_map},
                {"pastes", o.pastes},
                {"maps", maps},
                {"analysis_hash", analysis.hash},
                {"analysis_cached", analysis.from_cache},
                {"analysis_seconds", analysis.seconds},
                {"synthesis_seconds", stats.seconds},
                {"strips", stats.strips},
                {"device", ocl::Runtime::instance().device().name}});
  } else if (!global.quiet) {
    std::printf("%s: %dx%d at (%lld, %lld) from %s (%dx%d, %s) seed %u in %s (analysis %s)\n", o.output.c_str(),
                window.width, window.height, static_cast<long long>(window.x), static_cast<long long>(window.y),
                ex.name.c_str(), analysis.width, analysis.height, analysis.toroidal ? "tiles" : "bounded",
                options.seed, format_seconds(stats.seconds).c_str(),
                analysis.from_cache ? "cached" : format_seconds(analysis.seconds).c_str());
  }
}

}  // namespace

void add_synth_command(CLI::App& app, GlobalOptions& global) {
  auto o = std::make_shared<SynthCliOptions>();
  auto* cmd = app.add_subcommand("synth", "Synthesise more of a texture from a small example image (exemplar)");
  cmd->footer(
      "Parallel controllable texture synthesis (Lefebvre & Hoppe 2005, appearance space 2006) on OpenCL.\n"
      "The output is a window of an infinite plane: the same seed and options give the same pixels for\n"
      "the same place whatever window is asked, so big maps can be made in pieces that fit exactly.\n"
      "  proctex synth rocks.png -o big.png --size 2048\n"
      "  proctex synth rocks.png -o tile.png --size 1024 --tileable\n"
      "  proctex synth rocks.png -o part.png --window -4096,8192,512,512 --seed 7\n"
      "  proctex synth rocks.png -o out.png --apply normal=rocks_n.png:out_n.png --apply rocks_h.png:out_h.png\n"
      "  proctex synth rocks.png -o out.png --randomness 1,1,0.6,0.3   # coarse levels first\n"
      "  proctex synth --graph g.json -o map.png --size 16384 --zoom 6   # multiscale exemplar graph\n"
      "The analysis (Gaussian stack, appearance space, k-coherence) is cached in $PROCTEX_CACHE_DIR/synth\n"
      "(default ~/.cache/proctex/synth) under the exemplar's content hash.");
  cmd->add_option("exemplar", o->exemplar, "Example image (PNG, JPEG, TIFF, EXR), 16..512 px per side (required "
                                           "unless --graph)");
  cmd->add_option("-o,--output", o->output, "Output image (.png, .tif, .exr, .jpg)")->required();
  cmd->add_option("--size", o->size, "Output size WxH or N (also the period with --tileable)")->capture_default_str();
  cmd->add_option("--window", o->window,
                  "Synthesise only the window x,y,w,h of the infinite plane (offsets may be negative or huge)");
  cmd->add_option("--seed", o->seed, "Seed of every random choice")->capture_default_str()->check(
      CLI::Range(int64_t(0), int64_t(0xffffffff)));
  cmd->add_option("--randomness", o->randomness,
                  "Jitter per level, one value or a list coarse to fine, in units of the level's spacing (0 = "
                  "tiling; the default 1,0 moves the first level's blocks anywhere in the exemplar and keeps "
                  "finer levels coherent; large fine values change the detail; with --graph the last value "
                  "repeats for deeper levels, 1,1,0.5,0.3 suits deep zooms)")
      ->capture_default_str();
  cmd->add_option("--passes", o->passes,
                  "Correction passes per level (each has 4 sub-passes), one value or a list coarse to fine, 0..8 "
                  "(with --graph: the last value, at every level)")
      ->capture_default_str();
  cmd->add_option("--finest-passes", o->finest_passes,
                  "Correction passes at the finest level (the costliest), overriding --passes there; -1 = as --passes")
      ->capture_default_str()->check(CLI::Range(-1, 8));
  cmd->add_option("--refine-seams", o->refine_passes,
                  "Seam refinement passes at the finest level (0..8): pixels on a join between patches take "
                  "the neighbouring patch whose 9x9 surroundings match best")
      ->capture_default_str()->check(CLI::Range(0, 8));
  cmd->add_option("--rematch", o->rematch_passes,
                  "Final re-match passes at the finest level (0..8): pixels on a join take, among their "
                  "neighbours' patches and k-coherence candidates, the one whose 7x7 texels match best")
      ->capture_default_str()->check(CLI::Range(0, 8));
  cmd->add_option("--rematch-candidates", o->rematch_candidate_passes,
                  "How many re-match passes, from the first, also try the k-coherence candidates (0..8; later "
                  "passes try only the neighbours' patches; 2 with --finest-passes 1 = the earlier defaults: "
                  "~25% more CPU for 0.01 better median bench coherence)")
      ->capture_default_str()->check(CLI::Range(0, 8));
  cmd->add_option("--layout-shifts", o->layout_shifts,
                  "Shift the first level's blocks only by the exemplar's K most self-similar translations "
                  "(keeps rows and lattices aligned; 0 = any random shift)")
      ->capture_default_str()->check(CLI::Range(0, synth::kMaxShifts));
  cmd->add_option("--layout-min-correlation", o->layout_min_correlation,
                  "Use the layout shifts only when the exemplar correlates with itself under them at least this "
                  "much on average (-1..1; stochastic exemplars get uniform random shifts; -1 = always)")
      ->capture_default_str()->check(CLI::Range(-1.0f, 1.0f));
  cmd->add_option("--break-pieces", o->break_pieces,
                  "Probability (0..1) that a second-level block takes a further layout shift: cuts large "
                  "verbatim copies of the exemplar into smaller pieces")
      ->capture_default_str()->check(CLI::Range(0.0f, 1.0f));
  cmd->add_option("--coherence", o->kappa,
                  "Preference for growing patches over other similar texels (0 = none; larger keeps bigger pieces; "
                  "default 32, 8 with --graph)")
      ->check(CLI::Range(0.0f, 100.0f));
  cmd->add_option("--candidates", o->candidates,
                  "k of the k-coherence candidates: every exemplar texel's own position plus 1 (k = 2) or 2 "
                  "(k = 3) similar texels elsewhere, found by the analysis (k = 3: a second analysis cache entry)")
      ->capture_default_str()->check(CLI::Range(2, 3));
  cmd->add_option("--jitter-map", o->jitter_map,
                  "Grey image scaling the randomness per output pixel (white = --randomness, black = none); it "
                  "repeats over the plane from (0, 0)");
  cmd->add_option("--paste", o->pastes,
                  "Drag and paste a feature: EX_X,EX_Y,W,H@X,Y puts that exemplar rectangle at (X, Y) of the "
                  "plane, blended at its border; repeatable")
      ->allow_extra_args(false);
  cmd->add_flag("--tileable", o->tileable, "Make the output tile seamlessly with period --size");
  cmd->add_option("--blend-seams", o->blend_seams,
                  "on|off|N: ramp the colour (and --apply maps) across the joins between copied patches over N "
                  "pixels on either side (on = 4); the coordinates (--coords) stay exact and inside a patch "
                  "the pixels are exact copies")
      ->capture_default_str();
  cmd->add_option("--exemplar-tiles", o->exemplar_tiles,
                  "Whether the exemplar itself tiles: auto (measure the seam), yes, no")->capture_default_str();
  cmd->add_option("--coords", o->coords, "Also write the exemplar coordinate map (.exr: R = x, G = y in pixels; with --graph B = the exemplar index)");
  cmd->add_option("--apply", o->apply,
                  "Carry an aligned map through the same synthesis: [KIND=]IN:OUT, KIND = normal, height, "
                  "roughness, grey or colour (guessed from the file name); repeatable")
      ->allow_extra_args(false);
  cmd->add_option("--map-weight", o->map_weight, "Weight of the --apply maps in the matching (0 = colour only)")
      ->capture_default_str();
  cmd->add_option("--bits", o->bits, "Bit depth of PNG/TIFF output: 8 or 16 (default PNG 8, TIFF 16)");
  cmd->add_option("--png-compression", o->png_compression,
                  "Deflate level of PNG outputs, 0-9: 1 (default) is fast, 9 the smallest files (~3x slower to write)")
      ->check(CLI::Range(0, 9));
  cmd->add_option("--cache-dir", o->cache_dir, "Folder for cached analyses (default $PROCTEX_CACHE_DIR/synth)");
  cmd->add_flag("--no-cache", o->no_cache, "Analyse again and do not cache");
  cmd->add_flag("--json", o->json, "Print what was synthesised as JSON");
  cmd->add_option("--graph", o->graph,
                  "Multiscale exemplar graph (Han): a JSON file of exemplars and edges {from, to, scale} instead "
                  "of one exemplar; see docs/synth.md");
  cmd->add_option("--zoom", o->zoom,
                  "With --graph: output scale, an output pixel spans 2^-ZOOM root exemplar pixels (a self edge "
                  "zooms without end)")->capture_default_str();
  cmd->callback([o, &global] { run(*o, global); });
}

}  // namespace proctex::cli
