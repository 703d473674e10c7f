// proctex morph A B [KEY...]: a smooth transformation sequence between textures (thesis chapter 5).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <filesystem>
#include <memory>
#include <regex>

#include <fmt/format.h>

#include "catalog/catalog.h"
#include "core/parallel.h"
#include "catalog/store.h"
#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "image/image.h"
#include "search/match.h"
#include "shaders/renderer.h"
#include "transform/morph.h"

namespace proctex::cli {
namespace {

namespace fs = std::filesystem;

struct MorphCli {
  std::vector<std::string> inputs;
  std::string db, output, gif, sheet;
  int frames = 120, size = 512, dissolve = 0, depth = 6, max_renders = 800, fps = 24, gif_size = 256, jobs = 0;
  double power = 3.0, threshold = 0.9;
  long anchor_evaluations = 160;
  bool json = false, no_compare = false, no_connective = false, blend_steps = false, no_anchor = false;
};

bool is_photo(const std::string& arg) {
  static const std::set<std::string> kExt = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".bmp", ".webp"};
  std::error_code ec;
  std::string ext = fs::path(arg).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  return kExt.count(ext) && fs::is_regular_file(arg, ec);
}

// A spec file, an inline spec, or a photo (matched first).
TextureSpec read_input(const std::string& arg, catalog::Store& store, bool quiet) {
  if (!is_photo(arg)) return parse_spec_argument(arg);
  Progress progress("match " + fs::path(arg).filename().string(), 0, quiet);
  const auto r = search::match(search::prepare_target(arg, ""), store, {}, [&](const search::MatchProgress& p) {
    progress.update(0, fmt::format("{}  best {:.3f} {}", p.stage, p.best, p.best_shader));
  });
  progress.finish();
  if (!quiet)
    std::fprintf(stderr, "%s: matched %s (similarity %.3f, %s)\n", arg.c_str(), r.spec.shader.c_str(), r.similarity,
                 r.verdict.c_str());
  return r.spec;
}

// Frame files of an earlier, longer run would mix with this one: only our own names are removed.
void remove_old_frames(const fs::path& dir) {
  static const std::regex kFrame(R"(frame_\d+\.png)");
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && std::regex_match(e.path().filename().string(), kFrame)) fs::remove(e.path(), ec);
}

std::vector<size_t> sheet_columns(size_t frames, size_t columns) {
  std::vector<size_t> idx;
  const size_t n = std::min(frames, columns);
  for (size_t i = 0; i < n; ++i) idx.push_back(n == 1 ? 0 : i * (frames - 1) / (n - 1));
  return idx;
}

// Morph frames on the first row, the linear baseline at the same frame indices below.
Image make_sheet(const std::vector<transform::Frame>& morph, const std::vector<Image>& morph_tiles,
                 const std::vector<transform::Frame>& linear, const std::vector<Image>& linear_tiles, int tile) {
  const auto idx = sheet_columns(morph.size(), 8);
  std::vector<Image> tiles;
  std::vector<std::string> labels;
  auto label = [](const char* what, size_t i, const transform::Frame& f) {
    return std::isnan(f.similarity) ? fmt::format("{} {}", what, i) : fmt::format("{} {} S={:.2f}", what, i, f.similarity);
  };
  for (size_t i : idx) {
    tiles.push_back(resize(morph_tiles[i], tile, tile));
    labels.push_back(label("morph", i, morph[i]));
  }
  if (!linear_tiles.empty())
    for (size_t i : idx) {
      tiles.push_back(resize(linear_tiles[i], tile, tile));
      labels.push_back(label("linear", i, linear[i]));
    }
  return contact_sheet(tiles, labels, static_cast<int>(idx.size()), tile);
}

void print_human(const transform::Morph& m, const MorphCli& c, const nlohmann::json& written) {
  std::string route;
  for (const auto& s : m.shaders) route += (route.empty() ? "" : " -> ") + s;
  std::printf("morph: %s, %zu frames, %d jump(s), %zu waypoints (%d from the graph), seed %u\n", route.c_str(),
              m.frames.size(), m.jumps, m.path.size(), m.stats["graph_waypoints"].get<int>(), m.seed);
  const int unreached = m.unreached_count();
  if (unreached)
    std::printf("subdivision: %d edge(s) stay below similarity %.2f (see manifest 'unreached')\n", unreached, c.threshold);
  std::vector<std::vector<std::string>> rows = {{"sequence", "max 1-S", "mean 1-S", "worst frame", "layout mean", "layout max"}};
  auto row = [&](const char* name, const transform::Quality& q) {
    rows.push_back({name, fmt::format("{:.3f}", q.max_dissimilarity), fmt::format("{:.3f}", q.mean_dissimilarity),
                    std::to_string(q.worst_step), fmt::format("{:.4f}", q.layout_mean), fmt::format("{:.4f}", q.layout_max)});
  };
  if (m.quality) row("morph", *m.quality);
  if (m.linear) row("linear", *m.linear);
  if (m.quality) print_table(rows);
  if (m.quality && m.linear)
    std::printf("%s\n", m.quality->max_dissimilarity < m.linear->max_dissimilarity
                            ? "the morph beats linear interpolation on max adjacent dissimilarity"
                            : "the morph does NOT beat linear interpolation on max adjacent dissimilarity");
  for (const auto& w : m.warnings) std::printf("warning: %s\n", w.c_str());
  for (const auto& [k, v] : written.items()) std::printf("wrote %s\n", v.get<std::string>().c_str());
}

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void run(const MorphCli& c, const GlobalOptions& global) {
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json timings = nlohmann::json::object();
  const fs::path db = c.db.empty() ? catalog::default_catalog_path() : fs::path(c.db);
  if (!fs::exists(db))
    throw Error("no catalogue at '" + db.string() + "'", "build one: proctex catalog build --db " + db.string());
  catalog::Store store(db, catalog::Store::Access::Read);
  std::vector<TextureSpec> inputs;
  for (const auto& a : c.inputs) inputs.push_back(read_input(a, store, global.quiet));

  transform::MorphOptions o;
  o.frames = c.frames;
  o.power = c.power;
  o.threshold = c.threshold;
  o.max_depth = c.depth;
  o.max_renders = c.max_renders;
  o.dissolve = c.dissolve;
  o.connective = !c.no_connective;
  o.anchor = !c.no_anchor;
  o.anchor_evaluations = c.anchor_evaluations;
  o.blend_steps = c.blend_steps;
  o.jobs = c.jobs;
  if (!c.output.empty()) check_dimensions(c.size, c.size);

  Renderer renderer;
  auto progress = std::make_unique<Progress>("morph", 100, global.quiet);
  transform::Morph m = transform::plan(inputs, store, renderer, o, [&](const transform::MorphProgress& p) {
    progress->update(static_cast<long>(100 * p.fraction), p.stage);
  });
  progress->finish();
  timings["plan"] = since(t0);

  // Quality of the morph and of the naive baseline, at the catalogue's analysis resolution.
  const int tile = 128;
  std::vector<Image> morph_tiles, linear_tiles;
  std::vector<transform::Frame> linear;
  progress = std::make_unique<Progress>("measure", 100, global.quiet);
  m.quality = transform::measure(m.frames, renderer, m.resolution, c.jobs, &morph_tiles, tile,
                                 [&](double f) { progress->update(static_cast<long>(50 * f), "morph frames"); });
  if (!c.no_compare) {
    linear = transform::linear_frames(inputs, static_cast<int>(m.frames.size()), renderer.library());
    m.linear = transform::measure(linear, renderer, m.resolution, c.jobs, &linear_tiles, tile,
                                  [&](double f) { progress->update(50 + static_cast<long>(50 * f), "linear baseline"); });
  }
  progress->finish();
  timings["measure"] = since(t0) - timings["plan"].get<double>();

  const auto t_frames = std::chrono::steady_clock::now();
  nlohmann::json written = nlohmann::json::object();
  std::vector<Image> gif_frames;
  if (!c.output.empty()) {
    const fs::path dir(c.output);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (!fs::is_directory(dir)) throw Error("cannot create output folder '" + dir.string() + "'", "pass a writable -o folder");
    remove_old_frames(dir);
    RenderSettings rs;
    rs.width = rs.height = c.size;
    const int digits = std::max<int>(4, static_cast<int>(std::to_string(m.frames.size()).size()));
    progress = std::make_unique<Progress>("frames", static_cast<long>(m.frames.size()), global.quiet);
    nlohmann::json manifest = m.manifest();
    double render_seconds = 0;
    const size_t chunk = std::max<size_t>(1, (64u << 20) / (size_t(c.size) * c.size * 12));  // ~64 MB of renders
    for (size_t first = 0; first < m.frames.size(); first += chunk) {
      const auto t_render = std::chrono::steady_clock::now();
      const auto images = transform::render_frames(m.frames, first, chunk, renderer, rs);
      render_seconds += since(t_render);
      // PNG encoding costs as much as rendering: one file per thread.
      std::vector<Image> small(images.size());
      const int gif_side = std::min(c.gif_size, c.size);
      parallel_for(images.size(), c.jobs, [&](size_t k) {
        save_image(images[k], dir / fmt::format("frame_{:0{}d}.png", first + k + 1, digits));
        if (!c.gif.empty()) small[k] = resize(images[k], gif_side, gif_side);
      });
      for (size_t k = 0; k < images.size(); ++k) {
        manifest["frames"][first + k]["file"] = fmt::format("frame_{:0{}d}.png", first + k + 1, digits);
        if (!c.gif.empty()) gif_frames.push_back(std::move(small[k]));
      }
      progress->update(static_cast<long>(std::min(m.frames.size(), first + chunk)));
    }
    progress->finish();
    timings["frames_render"] = render_seconds;
    written["frames"] = (dir / fmt::format("frame_{:0{}d}.png .. {}", 1, digits, m.frames.size())).string();
    const fs::path sheet = c.sheet.empty() ? dir / "sheet.png" : fs::path(c.sheet);
    save_image(make_sheet(m.frames, morph_tiles, linear, linear_tiles, tile), sheet);
    written["sheet"] = sheet.string();
    manifest["sheet"] = sheet.string();
    write_text_file((dir / "manifest.json").string(), manifest.dump(2) + "\n");
    written["manifest"] = (dir / "manifest.json").string();
  } else if (!c.sheet.empty()) {
    save_image(make_sheet(m.frames, morph_tiles, linear, linear_tiles, tile), c.sheet);
    written["sheet"] = c.sheet;
  }
  if (!c.gif.empty()) {
    if (gif_frames.empty()) {  // no -o: the GIF from fresh renders at the GIF size
      RenderSettings rs;
      rs.width = rs.height = c.gif_size;
      gif_frames = transform::render_frames(m.frames, 0, m.frames.size(), renderer, rs);
    }
    transform::write_gif(gif_frames, c.gif, c.fps);
    written["gif"] = c.gif;
  }
  timings["frames"] = since(t_frames);
  timings["total"] = since(t0);
  if (c.json) {
    nlohmann::json j = m.summary();
    j["timings"] = timings;
    j["catalogue"] = db.string();
    j["written"] = written;
    return print_json(j);
  }
  print_human(m, c, written);
}

}  // namespace

void add_morph_command(CLI::App& app, GlobalOptions& global) {
  auto c = std::make_shared<MorphCli>();
  auto* cmd = app.add_subcommand("morph", "A smooth transformation sequence between textures (frames, sheet, GIF)");
  cmd->footer(
      "Inputs in order: first, optional key textures, last. Each is a spec file (JSON), an inline spec\n"
      "(bricks:rows=8,mortar=0.05) or a photo, which is matched first (proctex match).\n"
      "Within one shader the path walks the catalogue graph (Dijkstra, cost (sum e^n)^(1/n), e = 1 - S),\n"
      "then halves steps in parameter space until neighbours reach --threshold; frames are spaced evenly\n"
      "in perceptual distance, with the seed and texture domain fixed so noise does not flicker.\n"
      "Between shaders it crosses jump edges made by 'proctex catalog link' (possibly through a\n"
      "connective shader) or jumps anchored at the keys; --dissolve K cross-fades K frames at each jump,\n"
      "timed so each dissolve frame changes the look by the same amount.\n"
      "Reports the max and mean adjacent dissimilarity (1 - S) and layout stability (mean absolute\n"
      "difference of adjacent frames) for the morph and for naive linear interpolation.\n"
      "  proctex morph day.json night.json --frames 120 -o frames/ --gif morph.gif\n"
      "  proctex morph 'bricks:rows=6' 'bricks:rows=20,mortar=0.2' --frames 60 -o out/ --json\n"
      "  proctex morph rectangle circle --dissolve 4 -o shapes/   (after catalog link)");
  cmd->add_option("inputs", c->inputs, "Two or more textures: spec file, inline spec or photo")->required()->expected(2, -1);
  cmd->add_option("--db", c->db, "Catalogue (default: $PROCTEX_CATALOG or ~/.cache/proctex/catalog.sqlite)");
  cmd->add_option("--frames,-n", c->frames, "Frames in the sequence, inputs included")->capture_default_str()->check(CLI::Range(2, 100000));
  cmd->add_option("-o,--output", c->output, "Folder for frame_NNNN.png, sheet.png and manifest.json");
  cmd->add_option("--size", c->size, "Frame size in pixels")->capture_default_str()->check(CLI::Range(16, 65536));
  cmd->add_option("--gif", c->gif, "Also write an animated GIF here");
  cmd->add_option("--gif-size", c->gif_size, "GIF frame size")->capture_default_str()->check(CLI::Range(16, 2048));
  cmd->add_option("--fps", c->fps, "GIF frames per second")->capture_default_str()->check(CLI::Range(1, 100));
  cmd->add_option("--sheet", c->sheet, "Contact sheet path (default: OUTPUT/sheet.png); morph row above linear row");
  cmd->add_option("--power", c->power, "Path cost exponent n of eq 5.1 (larger: more, smaller steps)")->capture_default_str()->check(CLI::Range(1.0, 16.0));
  cmd->add_option("--threshold", c->threshold, "Subdivide until adjacent waypoints reach this similarity")->capture_default_str()->check(CLI::Range(0.01, 0.999));
  cmd->add_option("--depth", c->depth, "Maximum halvings per catalogue edge")->capture_default_str()->check(CLI::Range(0, 16));
  cmd->add_option("--max-renders", c->max_renders, "Render budget of the subdivision")->capture_default_str()->check(CLI::Range(0, 1000000));
  cmd->add_option("--dissolve", c->dissolve, "Least number of cross-faded frames at each jump between shaders (more when the cross-fade is long)")->capture_default_str()->check(CLI::Range(0, 1000));
  cmd->add_flag("--no-connective", c->no_connective, "Between shaders, only direct jump edges (no third shader)");
  cmd->add_flag("--no-anchor", c->no_anchor,
                "Between shaders, only the stored jump edges (default: also jumps anchored at the keys, found now:\n"
                "the point of each linked shader that looks most like the key)");
  cmd->add_option("--anchor-evaluations", c->anchor_evaluations, "Renders per anchored jump")->capture_default_str()->check(CLI::Range(1, 100000));
  cmd->add_flag("--blend-steps", c->blend_steps,
                "Frames inside a whole step of a discrete parameter cross-fade its two ends (default: they pop;\n"
                "cross-fades change the layout less but are less similar to their neighbours)");
  cmd->add_flag("--no-compare", c->no_compare, "Skip the linear-interpolation baseline");
  cmd->add_option("--jobs,-j", c->jobs, "Threads for the texture metric (0 = all cores)")->capture_default_str();
  cmd->add_flag("--json", c->json, "Print the summary and quality report as JSON");
  cmd->callback([c, &global] { run(*c, global); });
}

}  // namespace proctex::cli
