// proctex match over a folder or a list of photos (cli/match_batch.h).
#include <algorithm>
#include <atomic>
#include <cctype>
#include <csignal>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "catalog/catalog.h"
#include "catalog/store.h"
#include "cli/match_batch.h"
#include "cli/output.h"
#include "core/error.h"
#include "core/hash.h"
#include "core/version.h"
#include "search/selection.h"

namespace proctex::cli {
namespace fs = std::filesystem;

namespace {

std::atomic<bool> g_batch_stop{false};
extern "C" void on_batch_interrupt(int) { g_batch_stop = true; }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool is_list_file(const fs::path& p) {
  const std::string ext = lower(p.extension().string());
  return ext == ".txt" || ext == ".lst" || ext == ".list";
}

bool is_image_file(const fs::path& p) {
  static const std::set<std::string> exts = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr",
                                             ".bmp", ".webp", ".hdr", ".tga", ".ppm", ".pgm"};
  return exts.count(lower(p.extension().string())) > 0;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw Error("cannot read '" + p.string() + "'", "check the path and its permissions");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// "sub/dir/brick.jpg" -> "sub__dir__brick.jpg.json": one flat folder, names stay readable.
std::string result_name(const std::string& name) {
  std::string out;
  for (size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (c == '/' || c == '\\') {
      if (!out.empty()) out += "__";
    } else if (c == ':' ) {
      out += '_';
    } else {
      out += c;
    }
  }
  while (out.rfind("..", 0) == 0) out.replace(0, 2, "up");
  return out + ".json";
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

nlohmann::json options_json(const search::MatchOptions& o, const std::string& crop) {
  nlohmann::json fixed = nlohmann::json::object();
  for (const auto& [k, v] : o.fixed) fixed[k] = v;
  return {{"shaders", o.shaders},
          {"candidate_shaders", o.candidate_shaders},
          {"shader_threshold", o.shader_threshold},
          {"screen", o.screen},
          {"screen_resolution", o.screen_resolution},
          {"race", o.race},
          {"starts", o.starts},
          {"resolution", o.resolution},
          {"coarse_resolution", o.coarse_resolution},
          {"optimizer", search::to_string(o.refine.optimizer)},
          {"initial_step", o.refine.initial_step},
          {"tolerance", o.refine.tolerance},
          {"max_restarts", o.refine.max_restarts},
          {"max_evaluations", o.refine.max_evaluations},
          {"sweep_levels", o.refine.sweep_levels},
          {"probe_bounds", o.refine.probe_bounds},
          {"budget", {{"evaluations", o.budget.max_evaluations}, {"seconds", o.budget.max_seconds}}},
          {"fixed", fixed},
          {"selection_weight", o.selection_weight},
          {"polish_evaluations", o.polish_evaluations},
          {"selection_version", search::selection_version()},
          {"crop", crop}};
}

// Identifies the catalogue's content (not its file): every shader's content hash and metric.
std::string catalogue_hash(catalog::Store& store) {
  std::string text;
  for (const auto& s : store.shaders())
    text += s.name + ":" + s.content_hash + ":" + s.metric + ":" + std::to_string(s.metric_version) + ";";
  return fnv1a_hex(text);
}

struct Row {
  std::string photo, result, status, shader, verdict, error;
  double similarity = 0, seconds = 0;
  nlohmann::json to_json() const {
    nlohmann::json j = {{"photo", photo}, {"result", result}, {"status", status}, {"seconds", seconds}};
    if (status == "error") {
      j["error"] = error;
    } else {
      j["shader"] = shader;
      j["similarity"] = similarity;
      j["verdict"] = verdict;
    }
    return j;
  }
};

Row row_from_result(const std::string& photo, const std::string& file, const nlohmann::json& r, const std::string& status) {
  Row row;
  row.photo = photo;
  row.result = file;
  row.seconds = r.value("seconds", 0.0);
  if (r.value("status", std::string()) == "error") {
    row.status = "error";
    row.error = r.value("error", std::string());
    return row;
  }
  row.status = status;
  const auto& m = r["match"];
  row.shader = m["spec"].value("shader", std::string());
  row.similarity = m.value("similarity", 0.0);
  row.verdict = m.value("verdict", std::string());
  return row;
}

void write_index(const fs::path& out_dir, const std::string& stem, const std::vector<Row>& rows, const nlohmann::json& head) {
  std::string csv = "photo,shader,similarity,verdict,status,seconds,result,error\n";
  nlohmann::json j = head;
  j["photos"] = nlohmann::json::array();
  for (const auto& r : rows) {
    csv += csv_field(r.photo) + "," + csv_field(r.shader) + "," +
           (r.status == "error" ? std::string() : fmt::format("{:.4f}", r.similarity)) + "," + csv_field(r.verdict) + "," +
           r.status + "," + fmt::format("{:.2f}", r.seconds) + "," + csv_field(r.result) + "," + csv_field(r.error) + "\n";
    j["photos"].push_back(r.to_json());
  }
  write_text_file((out_dir / (stem + ".csv")).string(), csv);
  write_text_file((out_dir / (stem + ".json")).string(), j.dump(2) + "\n");
}

}  // namespace

void add_match_batch_options(CLI::App& match, MatchBatchCli& batch) {
  batch.match = &match;
  auto* g = match.add_option_group("Batch", "Many photos: give a folder or a list file (.txt: one path per line) as PHOTO");
  g->add_option("--out-dir", batch.out_dir,
                "Batch: folder of the per-photo result JSONs and the index (index.csv, index.json); default ./proctex-match");
  g->add_option("--shard", batch.shard, "Batch: match shard i of n of the sorted photo list (e.g. a Slurm array task)")
      ->capture_default_str();
  g->add_flag("--force", batch.force, "Batch: match again photos whose result is current");
  match.footer(match.get_footer() +
               "\nBatch: proctex match photos/ --out-dir results/ [--shard 2/4] writes results/<photo>.json per photo\n"
               "and results/index.csv + index.json (shader, similarity, verdict). A rerun skips photos whose result\n"
               "is current (same photo bytes, options and catalogue); a bad photo is an error row, the batch goes on.");
}

bool is_match_batch(const std::string& input, const MatchBatchCli& batch) {
  std::error_code ec;
  return !batch.out_dir.empty() || fs::is_directory(input, ec) || (is_list_file(input) && fs::is_regular_file(input, ec));
}

std::vector<BatchPhoto> list_batch_photos(const std::string& input, const fs::path& skip) {
  std::vector<BatchPhoto> out;
  std::error_code ec;
  if (fs::is_directory(input, ec)) {
    const fs::path root(input);
    const fs::path skip_abs = skip.empty() ? fs::path() : fs::weakly_canonical(skip, ec);
    for (auto it = fs::recursive_directory_iterator(root, fs::directory_options::skip_permission_denied, ec);
         it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (ec) break;
      if (it->is_directory(ec) && !skip_abs.empty() && fs::weakly_canonical(it->path(), ec) == skip_abs) {
        it.disable_recursion_pending();
        continue;
      }
      if (!it->is_regular_file(ec) || !is_image_file(it->path())) continue;
      out.push_back({it->path(), fs::relative(it->path(), root, ec).generic_string()});
    }
    if (ec) throw Error("cannot list folder '" + input + "': " + ec.message(), "check the path and its permissions");
  } else if (is_list_file(input) && fs::is_regular_file(input, ec)) {
    const fs::path base = fs::path(input).parent_path();
    std::istringstream lines(read_file(input));
    for (std::string line; std::getline(lines, line);) {
      line.erase(0, line.find_first_not_of(" \t\r"));
      const auto end = line.find_last_not_of(" \t\r");
      line.erase(end == std::string::npos ? 0 : end + 1);
      if (line.empty() || line[0] == '#') continue;
      const fs::path p(line);
      out.push_back({p.is_absolute() ? p : base / p, fs::path(line).generic_string()});
    }
  } else if (fs::is_regular_file(input, ec)) {
    out.push_back({fs::path(input), fs::path(input).filename().generic_string()});
  } else {
    throw UsageError("no photo, folder or list file at '" + input + "'", "give a photo, a folder of photos or a .txt list");
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  out.erase(std::unique(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name == b.name; }), out.end());
  return out;
}

void run_match_batch(const std::string& input, const std::string& crop, const std::string& db_arg,
                     const search::MatchOptions& options, const MatchBatchCli& batch, bool json,
                     const GlobalOptions& global) {
  const catalog::Shard shard = catalog::Shard::parse(batch.shard);
  if (batch.match)
    for (const char* single : {"--output", "--render", "--compare"})
      if (batch.match->count(single) > 0)
        throw UsageError(std::string(single) + " is for one photo; a batch writes one result JSON per photo",
                         "drop " + std::string(single) + ": the results go to --out-dir");
  const fs::path out_dir = batch.out_dir.empty() ? fs::path("proctex-match") : fs::path(batch.out_dir);
  const auto all = list_batch_photos(input, out_dir);
  if (all.empty()) throw UsageError("no photos in '" + input + "'", "a folder of PNG/JPEG/TIFF/EXR files or a .txt list");
  std::vector<BatchPhoto> photos;  // round-robin over the sorted names: shards of similar size
  for (size_t i = 0; i < all.size(); ++i)
    if (static_cast<int>(i % shard.count) == shard.index - 1) photos.push_back(all[i]);

  const fs::path db = db_arg.empty() ? catalog::default_catalog_path() : fs::path(db_arg);
  if (!fs::exists(db)) throw Error("no catalogue at '" + db.string() + "'", "build one: proctex catalog build --db " + db.string());
  catalog::Store store(db, catalog::Store::Access::Read);
  catalog::require_current_sources(store);
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (!fs::is_directory(out_dir))
    throw Error("cannot create output folder '" + out_dir.string() + "'", "pass a writable --out-dir");

  const nlohmann::json opts = options_json(options, crop);
  const std::string options_hash = fnv1a_hex(opts.dump());
  const std::string cat_hash = catalogue_hash(store);
  const std::string stem = shard.count == 1 ? "index" : fmt::format("index-{}-of-{}", shard.index, shard.count);

  g_batch_stop = false;
  auto previous = std::signal(SIGINT, on_batch_interrupt);
  std::vector<Row> rows;
  int matched = 0, cached = 0, failed = 0;
  const bool lines = !global.quiet && !stderr_is_terminal();
  Progress progress(fmt::format("match {} {}", input, shard.str()), static_cast<long>(photos.size()), global.quiet);
  for (size_t i = 0; i < photos.size() && !g_batch_stop; ++i) {
    const auto& ph = photos[i];
    const std::string file = result_name(ph.name);
    const fs::path result_path = out_dir / file;
    progress.update(static_cast<long>(i), ph.name);
    std::string photo_hash;
    std::string read_error;
    try {
      photo_hash = fnv1a_hex(read_file(ph.path));
    } catch (const Error& e) {
      read_error = e.message();
    }
    // Current result: same photo bytes, options and catalogue -> reuse it.
    if (!batch.force && !photo_hash.empty() && fs::exists(result_path, ec)) {
      try {
        const auto r = nlohmann::json::parse(read_file(result_path));
        if (r.value("photo_hash", std::string()) == photo_hash && r.value("options_hash", std::string()) == options_hash &&
            r.value("catalogue_hash", std::string()) == cat_hash) {
          rows.push_back(row_from_result(ph.name, file, r, "cached"));
          ++cached;
          if (rows.back().status == "error") ++failed;
          if (lines) std::fprintf(stderr, "proctex: [%zu/%zu] %s: current result kept\n", i + 1, photos.size(), ph.name.c_str());
          continue;
        }
      } catch (const std::exception&) {
        // unreadable or old result: match again
      }
    }
    nlohmann::json r = {{"photo", ph.name},         {"path", ph.path.string()},      {"photo_hash", photo_hash},
                        {"options", opts},          {"options_hash", options_hash},  {"catalogue", db.string()},
                        {"catalogue_hash", cat_hash}, {"proctex_version", kVersion}};
    const auto t0 = std::chrono::steady_clock::now();
    try {
      if (!read_error.empty()) throw Error(read_error);
      const Image target = search::prepare_target(ph.path, crop);
      const auto result = search::match(target, store, options, {}, &g_batch_stop);
      if (g_batch_stop) break;  // interrupted: no result for a half search; a rerun redoes it
      nlohmann::json m = result.to_json();
      m["target"] = {{"path", ph.path.string()}, {"width", target.width}, {"height", target.height}, {"crop", crop}};
      r["status"] = "ok";
      r["match"] = m;
      ++matched;
    } catch (const Error& e) {
      r["status"] = "error";
      r["error"] = e.message() + (e.hint().empty() ? "" : " (" + e.hint() + ")");
      ++failed;
    } catch (const std::exception& e) {
      r["status"] = "error";
      r["error"] = std::string(e.what());
      ++failed;
    }
    r["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_text_file(result_path.string(), r.dump(2) + "\n");
    rows.push_back(row_from_result(ph.name, file, r, "matched"));
    if (lines) {
      const Row& row = rows.back();
      if (row.status == "error")
        std::fprintf(stderr, "proctex: [%zu/%zu] %s: error: %s\n", i + 1, photos.size(), ph.name.c_str(), row.error.c_str());
      else
        std::fprintf(stderr, "proctex: [%zu/%zu] %s: %s %.3f %s (%.1f s)\n", i + 1, photos.size(), ph.name.c_str(),
                     row.shader.c_str(), row.similarity, row.verdict.c_str(), row.seconds);
    }
  }
  progress.finish();
  std::signal(SIGINT, previous);
  const nlohmann::json head = {{"input", input},         {"shard", shard.str()},        {"photos_total", all.size()},
                               {"photos", photos.size()}, {"catalogue", db.string()},    {"catalogue_hash", cat_hash},
                               {"options", opts},        {"options_hash", options_hash}, {"proctex_version", kVersion}};
  write_index(out_dir, stem, rows, head);
  nlohmann::json summary = {{"out_dir", out_dir.string()}, {"index", (out_dir / (stem + ".csv")).string()},
                            {"shard", shard.str()},         {"photos", photos.size()},
                            {"matched", matched},           {"cached", cached},
                            {"failed", failed},             {"interrupted", g_batch_stop.load()}};
  if (json) {
    summary["rows"] = nlohmann::json::array();
    for (const auto& r : rows) summary["rows"].push_back(r.to_json());
    print_json(summary);
  } else {
    std::vector<std::vector<std::string>> table = {{"photo", "shader", "similarity", "verdict", "status"}};
    for (const auto& r : rows)
      table.push_back({r.photo, r.status == "error" ? "-" : r.shader,
                       r.status == "error" ? "-" : fmt::format("{:.3f}", r.similarity),
                       r.status == "error" ? r.error : r.verdict, r.status});
    print_table(table);
    std::printf("%s: %zu of %zu photos (shard %s), %d matched, %d current results kept, %d failed\n",
                (out_dir / (stem + ".csv")).string().c_str(), photos.size(), all.size(), shard.str().c_str(), matched,
                cached, failed);
  }
  if (g_batch_stop)
    throw Error("interrupted after " + std::to_string(rows.size()) + " of " + std::to_string(photos.size()) + " photos",
                "rerun the same command to continue: finished photos are kept");
  if (failed > 0) {
    std::string first;
    for (const auto& r : rows)
      if (r.status == "error") {
        first = r.photo + ": " + r.error;
        break;
      }
    throw Error(std::to_string(failed) + " of " + std::to_string(photos.size()) + " photos failed, first: " + first,
                "the other photos were matched; see " + (out_dir / (stem + ".csv")).string());
  }
}

}  // namespace proctex::cli
