// proctex compare: texture similarity of images.
//   proctex compare A B [--metric NAME|all] [--json]          one pair, one or every metric
//   proctex compare QUERY CANDIDATE... [--top K] [--json]     rank candidates (files or folders)
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "image/image.h"
#include "metrics/composite.h"
#include "metrics/metric.h"

namespace proctex::cli {
namespace {

namespace fs = std::filesystem;

struct CompareOptions {
  std::vector<std::string> images;
  std::string metric = "default";
  int top = 0;
  int resolution = metrics::kDefaultResolution;
  bool json = false;
};

bool is_image_file(const fs::path& p) {
  static const std::set<std::string> exts = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr",
                                             ".bmp", ".tga", ".hdr", ".webp"};
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return exts.count(e) > 0;
}

// A folder expands to the image files directly inside it, sorted by name.
std::vector<fs::path> expand(const std::vector<std::string>& args) {
  std::vector<fs::path> out;
  for (const auto& a : args) {
    fs::path p(a);
    if (fs::is_directory(p)) {
      std::vector<fs::path> found;
      for (const auto& e : fs::directory_iterator(p))
        if (e.is_regular_file() && is_image_file(e.path())) found.push_back(e.path());
      if (found.empty()) throw Error("folder '" + a + "' holds no images", "give image files or a folder of PNG/JPEG/TIFF/EXR files");
      std::sort(found.begin(), found.end());
      out.insert(out.end(), found.begin(), found.end());
    } else {
      out.push_back(p);
    }
  }
  return out;
}

void compare_pair(const fs::path& a, const fs::path& b, const CompareOptions& o) {
  const Image ia = load_image(a), ib = load_image(b);
  const metrics::Analysis aa = metrics::prepare_analysis(ia, o.resolution);
  const metrics::Analysis ab = metrics::prepare_analysis(ib, o.resolution);
  std::vector<std::string> names;
  if (o.metric == "all") names = metrics::metric_names();
  else names = {metrics::get_metric(o.metric).id()};
  nlohmann::json j = {{"a", a.string()}, {"b", b.string()}, {"resolution", o.resolution},
                      {"similarity", nlohmann::json::object()}};
  std::vector<std::vector<std::string>> rows = {{"metric", "similarity", "version", "description"}};
  for (const auto& n : names) {
    const metrics::Metric& m = metrics::get_metric(n);
    const double s = m.similarity(m.features(aa), m.features(ab));
    j["similarity"][m.id()] = s;
    rows.push_back({m.id(), fmt::format("{:.4f}", s), std::to_string(m.version()), m.summary()});
  }
  if (o.json) return print_json(j);
  if (names.size() == 1) {
    std::printf("%.4f\n", j["similarity"][names[0]].get<double>());
    return;
  }
  print_table(rows);
}

void rank(const fs::path& query, const std::vector<fs::path>& candidates, const CompareOptions& o,
          bool quiet) {
  const metrics::Metric& m = metrics::get_metric(o.metric == "all" ? "default" : o.metric);
  const auto* composite = dynamic_cast<const metrics::CompositeMetric*>(&m);
  const metrics::Features fq = m.features(load_image(query), o.resolution);
  struct Row {
    fs::path path;
    double similarity;
    std::vector<std::pair<std::string, double>> parts;
  };
  std::vector<Row> rows;
  Progress progress("features", static_cast<long>(candidates.size()), quiet);
  for (size_t i = 0; i < candidates.size(); ++i) {
    const metrics::Features fc = m.features(load_image(candidates[i]), o.resolution);
    Row r{candidates[i], m.similarity(fq, fc), {}};
    if (composite) r.parts = composite->breakdown(fq.values, fc.values);
    rows.push_back(std::move(r));
    progress.update(static_cast<long>(i + 1), candidates[i].filename().string());
  }
  progress.finish();
  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.similarity > b.similarity; });
  if (o.top > 0 && rows.size() > static_cast<size_t>(o.top)) rows.resize(o.top);
  if (o.json) {
    nlohmann::json j = {{"query", query.string()}, {"metric", m.id()}, {"version", m.version()},
                        {"resolution", o.resolution}, {"results", nlohmann::json::array()}};
    for (size_t i = 0; i < rows.size(); ++i) {
      nlohmann::json r = {{"rank", i + 1}, {"path", rows[i].path.string()}, {"similarity", rows[i].similarity}};
      for (const auto& [id, s] : rows[i].parts) r["components"][id] = s;
      j["results"].push_back(r);
    }
    return print_json(j);
  }
  std::vector<std::vector<std::string>> table;
  std::vector<std::string> header = {"rank", "similarity"};
  if (!rows.empty())
    for (const auto& p : rows[0].parts) header.push_back(p.first);
  header.push_back("image");
  table.push_back(header);
  for (size_t i = 0; i < rows.size(); ++i) {
    std::vector<std::string> line = {std::to_string(i + 1), fmt::format("{:.4f}", rows[i].similarity)};
    for (const auto& p : rows[i].parts) line.push_back(fmt::format("{:.3f}", p.second));
    line.push_back(rows[i].path.string());
    table.push_back(line);
  }
  print_table(table);
}

}  // namespace

void add_compare_command(CLI::App& app, GlobalOptions& global) {
  auto opts = std::make_shared<CompareOptions>();
  std::string metric_list;
  for (const auto& n : metrics::metric_names()) metric_list += (metric_list.empty() ? "" : ", ") + n;
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Texture similarity of images, in (0, 1] (1 = same texture statistics).\n"
      "  proctex compare A B                 similarity of two images (default metric)\n"
      "  proctex compare A B --metric all    every metric\n"
      "  proctex compare QUERY C1 C2 DIR/    rank candidates (a folder expands to its images)\n"
      "Images are centre-cropped to a square and resized to the analysis resolution; pixels are\n"
      "never compared, only texture statistics, so two crops of one texture score high.");
  cmd->add_option("images", opts->images, "QUERY and one or more candidate images or folders")
      ->required()
      ->expected(2, -1);
  cmd->add_option("--metric,-m", opts->metric,
                  "metric: " + metric_list + ", default (= composite) or all (pairs only)")
      ->capture_default_str();
  cmd->add_option("--top,-k", opts->top, "ranking: show only the K most similar candidates");
  cmd->add_option("--resolution", opts->resolution,
                  "analysis resolution in pixels (multiple of 16, 64..4096)")
      ->capture_default_str();
  cmd->add_flag("--json", opts->json, "machine-readable output on stdout");
  cmd->callback([opts, &global] {
    if (opts->metric != "all") {
      try {
        metrics::get_metric(opts->metric);
      } catch (const Error& e) {
        throw UsageError(e.message(), e.hint());  // a typo on the command line: exit 2
      }
    }
    const fs::path query = opts->images.front();
    std::vector<std::string> rest(opts->images.begin() + 1, opts->images.end());
    const std::vector<fs::path> candidates = expand(rest);
    const bool pair = opts->images.size() == 2 && !fs::is_directory(rest.front()) && opts->top == 0;
    if (pair) return compare_pair(query, candidates.front(), *opts);
    if (opts->metric == "all") {
      throw UsageError("--metric all compares one pair", "give exactly two images, or one metric for a ranking");
    }
    rank(query, candidates, *opts, global.quiet);
  });
}

}  // namespace proctex::cli
