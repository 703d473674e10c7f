#include "catalog/catalog.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include <sys/resource.h>

#include "catalog/thumbnail.h"
#include "core/error.h"
#include "core/version.h"
#include "kernels/runtime.h"
#include "shaders/renderer.h"

namespace proctex::catalog {
namespace fs = std::filesystem;

namespace {
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
// Process CPU time (every thread: feature workers and the PoCL device threads), seconds.
double cpu_now() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
int resolve_jobs(int jobs) { return jobs > 0 ? jobs : std::max(1u, std::thread::hardware_concurrency()); }
}  // namespace

fs::path default_catalog_path() {
  if (const char* p = std::getenv("PROCTEX_CATALOG"); p && *p) return p;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "proctex" / "catalog.sqlite";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache" / "proctex" / "catalog.sqlite";
  return "proctex-catalog.sqlite";
}

Shard Shard::parse(const std::string& text) {
  Shard s;
  const auto slash = text.find('/');
  try {
    if (slash == std::string::npos) throw std::invalid_argument(text);
    size_t a = 0, b = 0;
    s.index = std::stoi(text.substr(0, slash), &a);
    s.count = std::stoi(text.substr(slash + 1), &b);
    if (a != slash || b != text.size() - slash - 1) throw std::invalid_argument(text);
  } catch (const std::exception&) {
    throw UsageError("--shard must look like i/n, got '" + text + "'", "e.g. --shard 3/8 builds the third of eight shards");
  }
  if (s.count < 1 || s.index < 1 || s.index > s.count)
    throw UsageError("--shard " + text + " is out of range", "i must be in 1..n");
  return s;
}

std::vector<std::string> shard_shaders(std::vector<std::string> names, const Shard& shard,
                                       const std::map<std::string, double>& measured) {
  return plan_shards(names, shard.count, resolve_costs(names, measured)).shards.at(shard.index - 1);
}

std::vector<std::string> select_shaders(const ShaderLibrary& library, const std::string& list) {
  if (list.empty() || list == "all") return library.names();
  std::vector<std::string> out;
  std::stringstream ss(list);
  for (std::string name; std::getline(ss, name, ',');) {
    name.erase(0, name.find_first_not_of(" \t"));
    name.erase(name.find_last_not_of(" \t") + 1);
    if (name.empty()) continue;
    out.push_back(library.get(name).name);  // UsageError with close matches
  }
  if (out.empty()) throw UsageError("--shaders names no shader", "use --shaders all or a comma-separated list");
  return out;
}

nlohmann::json BuildReport::to_json() const {
  nlohmann::json j = {{"db", db.string()}, {"shard", shard.str()}, {"seed", seed}, {"seconds", seconds},
                      {"device", device}, {"shaders", nlohmann::json::array()}};
  if (!plan.is_null())
    j["plan"] = {{"count", plan["count"]}, {"balance", plan["balance"]}, {"hash", plan["hash"]},
                 {"cost_source", plan["cost_source"]}, {"load", plan["shards"][shard.index - 1]["load"]},
                 {"slowest", plan["slowest"]}, {"total", plan["total"]}};
  for (const auto& r : shaders) {
    nlohmann::json s = {{"shader", r.shader}, {"status", r.status}, {"reason", r.reason}, {"seconds", r.seconds},
                        {"samples", r.samples}};
    if (r.coverage) s["coverage"] = r.coverage->to_json();
    if (!r.stats.is_null()) s["stats"] = r.stats;
    j["shaders"].push_back(s);
  }
  return j;
}

std::optional<CatalogueSettings> catalogue_settings(const std::filesystem::path& db) {
  if (!std::filesystem::exists(db)) return std::nullopt;
  Store store(db, Store::Access::Read);
  std::optional<CatalogueSettings> found;
  for (const ShaderSummary& s : store.shaders()) {
    CatalogueSettings c{SamplingSettings::from_json(s.settings), s.seed};
    if (!found) found = c;
    else if (found->settings.hash(found->seed) != c.settings.hash(c.seed)) return std::nullopt;
  }
  return found;
}

BuildReport build(const BuildOptions& o, const std::function<void(const BuildEvent&)>& progress,
                  const ShaderLibrary& library) {
  const auto t0 = Clock::now();
  o.settings.validate();
  std::vector<std::string> selected = o.shaders.empty() ? library.names() : o.shaders;
  for (const auto& n : selected) library.get(n);  // unknown names: UsageError before touching the file
  std::sort(selected.begin(), selected.end());
  selected.erase(std::unique(selected.begin(), selected.end()), selected.end());
  const ShaderCosts costs = resolve_costs(selected, o.costs.empty() ? std::map<std::string, double>{} : read_costs(o.costs),
                                          o.costs.empty() ? "" : o.costs.filename().string());
  const ShardPlan plan = plan_shards(selected, o.shard.count, costs);
  std::vector<std::string> names = plan.shards.at(o.shard.index - 1);
  const int jobs = resolve_jobs(o.jobs);

  Store store(o.db, Store::Access::Write);
  BuildReport report;
  report.db = o.db;
  report.shard = o.shard;
  report.seed = o.seed;
  report.plan = plan.to_json();
  const std::string settings_hash = o.settings.hash(o.seed);

  // Decide first (cheap), so progress knows how many shaders will really be built.
  std::vector<std::pair<std::string, std::string>> todo;  // name, reason
  for (const auto& name : names) {
    const ShaderDecl& decl = library.get(name);
    const auto existing = store.summary(name);
    ShaderResult r;
    r.shader = name;
    if (!existing) {
      todo.push_back({name, "new"});
      continue;
    }
    std::string why;
    if (existing->source_hash != decl.source_hash) why = "source changed";
    else if (existing->settings_hash != settings_hash) why = "settings or seed changed";
    else if (o.force) why = "forced";
    if (why.empty()) {
      r.status = "skipped";
      r.reason = "unchanged";
      r.samples = existing->samples;
      r.coverage = existing->coverage;
      r.seconds = existing->build_seconds;
      report.shaders.push_back(r);
    } else {
      todo.push_back({name, why});
    }
  }

  Renderer renderer(library);
  const std::string device = ocl::Runtime::instance().device().name;
  report.device = device;
  // What `catalog merge` checks across shard files: the whole plan (so a missing shard can be
  // named), and the source of every selected shader (shards from different checkouts differ here).
  nlohmann::json sources = nlohmann::json::object();
  for (const auto& n : selected) sources[n] = library.get(n).source_hash;
  const int64_t build_id = store.begin_build({{"command", "build"}, {"seed", o.seed}, {"settings", o.settings.to_json()},
                                              {"shard", o.shard.str()}, {"shaders", names}, {"jobs", jobs},
                                              {"proctex_version", kVersion}, {"device", device},
                                              {"plan", report.plan}, {"sources", sources}});
  for (size_t i = 0; i < todo.size(); ++i) {
    const auto& [name, why] = todo[i];
    const ShaderDecl& decl = library.get(name);
    const auto ts = Clock::now();
    const double cpu0 = cpu_now();
    auto on_progress = [&, i](const SamplingProgress& p) {
      if (progress) progress({name, static_cast<int>(i), static_cast<int>(todo.size()), p.stage, p.fraction});
    };
    ShaderCatalogue cat;
    try {
      cat = sample_shader(decl, o.settings, o.seed, renderer, jobs, on_progress);
    } catch (const UsageError&) {
      throw;
    } catch (const Error& e) {
      throw Error("building the catalogue of shader '" + name + "': " + e.message(),
                  e.hint().empty() ? "shaders built before this one are saved; rerun to continue" : e.hint());
    }
    const double seconds = since(ts);
    const double cpu = cpu_now() - cpu0;
    store.write(cat, device, seconds, cpu);  // one transaction: the shader appears complete or not at all
    ShaderResult r;
    r.shader = name;
    r.status = why == "new" ? "built" : "rebuilt";
    r.reason = why;
    r.seconds = seconds;
    r.samples = static_cast<int>(cat.samples.size());
    if (cat.coverage.probes > 0) r.coverage = cat.coverage;
    r.stats = cat.stats;
    report.shaders.push_back(r);
  }
  std::sort(report.shaders.begin(), report.shaders.end(), [](const auto& a, const auto& b) { return a.shader < b.shader; });
  report.seconds = since(t0);
  nlohmann::json result = nlohmann::json::object();
  for (const auto& r : report.shaders) result[r.shader] = {{"status", r.status}, {"seconds", r.seconds}};
  store.finish_build(build_id, {{"shaders", result}, {"seconds", report.seconds}});
  return report;
}

nlohmann::json MergeReport::to_json() const {
  return {{"out", out.string()},   {"inputs", inputs},          {"added", added},          {"unchanged", unchanged},
          {"linked", linked},       {"linked_before", linked_before}, {"jump_edges", jump_edges}};
}

namespace {

// One merge participant as the agreement checks see it.
struct Participant {
  fs::path path;
  std::vector<ShaderSummary> shaders;
  nlohmann::json build;  // the file's last `catalog build` row (null: none, e.g. a merged file)
};

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

std::string value_text(const nlohmann::json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

// First difference between two shaders' build settings: {what, value in b, value in a}; empty
// `what` when they agree.
struct Difference {
  std::string what, b, a;
};
Difference settings_difference(const ShaderSummary& a, const ShaderSummary& b) {
  if (a.seed != b.seed) return {"seed", std::to_string(b.seed), std::to_string(a.seed)};
  if (a.metric != b.metric) return {"metric", b.metric, a.metric};
  if (a.metric_version != b.metric_version)
    return {"metric version (" + a.metric + ")", std::to_string(b.metric_version), std::to_string(a.metric_version)};
  std::set<std::string> keys;
  for (const auto* j : {&a.settings, &b.settings})
    if (j->is_object())
      for (const auto& [k, v] : j->items()) keys.insert(k);
  keys.erase("batch");  // launch size: not part of the settings hash, results are identical
  for (const auto& k : keys) {
    const nlohmann::json va = a.settings.is_object() && a.settings.contains(k) ? a.settings[k] : nlohmann::json();
    const nlohmann::json vb = b.settings.is_object() && b.settings.contains(k) ? b.settings[k] : nlohmann::json();
    if (va != vb) return {"setting " + k, value_text(vb), value_text(va)};
  }
  return {};
}

void check_agreement(const std::vector<Participant>& parts) {
  const std::string hint =
      "build every shard with the same proctex checkout, --seed and settings (--allow-mixed merges anyway; nothing was "
      "merged)";
  // Settings, seeds, metric versions: every shader against the first shader seen.
  const ShaderSummary* ref = nullptr;
  const Participant* ref_part = nullptr;
  for (const auto& p : parts)
    for (const auto& s : p.shaders) {
      if (!ref) {
        ref = &s;
        ref_part = &p;
        continue;
      }
      const Difference d = settings_difference(*ref, s);
      if (!d.what.empty())
        throw Error("cannot merge: " + quoted(p.path) + " (shader '" + s.name + "') was built with " + d.what + " = " +
                        d.b + ", " + quoted(ref_part->path) + " (shader '" + ref->name + "') with " + d.a,
                    hint);
    }
  // Shader sources: wherever two files know a shader (its rows, or the sources a build recorded).
  auto known_sources = [](const Participant& p) {
    std::map<std::string, std::string> m;
    if (p.build.is_object() && p.build.contains("sources") && p.build["sources"].is_object())
      for (const auto& [k, v] : p.build["sources"].items()) m[k] = v.get<std::string>();
    for (const auto& s : p.shaders) m[s.name] = s.source_hash;  // the rows are what was built
    return m;
  };
  std::vector<std::map<std::string, std::string>> sources;
  for (const auto& p : parts) sources.push_back(known_sources(p));
  for (size_t b = 1; b < parts.size(); ++b)
    for (size_t a = 0; a < b; ++a)
      for (const auto& [name, hash] : sources[b]) {
        const auto it = sources[a].find(name);
        if (it != sources[a].end() && it->second != hash)
          throw Error("cannot merge: " + quoted(parts[b].path) + " was built from a different source of shader '" + name +
                          "' than " + quoted(parts[a].path) + " (source hash " + hash + " vs " + it->second + ")",
                      hint);
      }
}

void check_shards_complete(const std::vector<Participant>& inputs) {
  const std::string hint = "merge all n shard files of one build (--allow-partial merges what is there)";
  const Participant* first = nullptr;
  std::map<int, const Participant*> have;
  for (const auto& p : inputs) {
    if (!p.build.is_object() || !p.build.contains("plan") || !p.build["plan"].is_object()) continue;
    const Shard shard = Shard::parse(p.build.value("shard", std::string("1/1")));
    if (shard.count < 2) continue;
    if (!p.build.value("finished", false))
      throw Error("cannot merge: " + quoted(p.path) + " (shard " + shard.str() + ") did not finish its build",
                  "the job was killed or failed: rerun the same 'proctex catalog build --shard " + shard.str() +
                      "' command on that file, it continues where it stopped");
    if (!first) {
      first = &p;
    } else {
      const auto& fp = first->build["plan"];
      const auto& pp = p.build["plan"];
      if (fp["count"] != pp["count"])
        throw Error("cannot merge: " + quoted(p.path) + " is shard " + shard.str() + " but " + quoted(first->path) +
                        " is shard " + first->build.value("shard", std::string()) + ": shards of different splits",
                    hint);
      if (fp["hash"] != pp["hash"])
        throw Error("cannot merge: " + quoted(p.path) + " and " + quoted(first->path) +
                        " were split differently (shard plans " + value_text(pp["hash"]) + " vs " + value_text(fp["hash"]) +
                        ", cost sources " + value_text(pp["cost_source"]) + " vs " + value_text(fp["cost_source"]) + ")",
                    "give every shard the same --shaders and --costs");
    }
    if (have.count(shard.index)) continue;  // the same shard twice: its shaders are conflict-checked below
    have[shard.index] = &p;
  }
  if (!first) return;
  const auto& plan = first->build["plan"];
  const int n = plan["count"].get<int>();
  for (int i = 1; i <= n; ++i) {
    if (have.count(i)) continue;
    std::string shaders;
    for (const auto& s : plan["shards"][i - 1]["shaders"]) shaders += (shaders.empty() ? "" : ", ") + s.get<std::string>();
    std::string got;
    for (const auto& [k, p] : have) got += (got.empty() ? "" : ", ") + std::to_string(k) + "/" + std::to_string(n) + " " + quoted(p->path);
    throw Error("cannot merge: shard " + std::to_string(i) + "/" + std::to_string(n) + " is missing (it builds " +
                    shaders + "); got " + got,
                hint);
  }
}

Participant participant(const fs::path& path) {
  Participant p;
  p.path = path;
  Store s(path, Store::Access::Read);
  p.shaders = s.shaders();
  for (const auto& b : s.builds())
    if (b.value("command", std::string()) == "build" && b["info"].is_object()) {
      p.build = b["info"];
      p.build["finished"] = !b["finished_at"].is_null();
    }
  return p;
}

}  // namespace

MergeReport merge(const fs::path& out, const std::vector<fs::path>& inputs, const MergeOptions& options) {
  if (inputs.empty()) throw UsageError("catalog merge needs at least one input", "proctex catalog merge OUT IN...");
  {
    std::error_code ec0;
    std::vector<Participant> parts;
    if (fs::exists(out, ec0)) parts.push_back(participant(out));
    const size_t first_input = parts.size();
    for (const auto& in : inputs)
      if (!(fs::exists(out, ec0) && fs::equivalent(in, out, ec0))) parts.push_back(participant(in));
    if (!options.allow_mixed) check_agreement(parts);
    if (!options.allow_partial)
      check_shards_complete(std::vector<Participant>(parts.begin() + static_cast<long>(first_input), parts.end()));
  }
  struct Source {
    fs::path path;
    ShaderSummary summary;
  };
  std::map<std::string, Source> chosen;
  std::vector<std::string> conflicts;
  auto same = [](const ShaderSummary& a, const ShaderSummary& b) {
    return a.content_hash == b.content_hash && a.source_hash == b.source_hash && a.settings_hash == b.settings_hash;
  };
  std::error_code ec;
  for (const auto& in : inputs) {
    if (fs::exists(out, ec) && fs::equivalent(in, out, ec)) continue;
    Store s(in, Store::Access::Read);
    for (auto& sum : s.shaders()) {
      auto it = chosen.find(sum.name);
      if (it == chosen.end()) chosen[sum.name] = {in, sum};
      else if (!same(it->second.summary, sum))
        conflicts.push_back(sum.name + " (" + it->second.path.string() + " vs " + in.string() + ")");
    }
  }
  const bool existed = fs::exists(out, ec);
  MergeReport report;
  report.out = out;
  report.inputs = static_cast<int>(inputs.size());
  try {
    Store dst(out, Store::Access::Write);
    for (const auto& [name, src] : chosen) {
      const auto have = dst.summary(name);
      if (have && !same(*have, src.summary))
        conflicts.push_back(name + " (" + out.string() + " vs " + src.path.string() + ")");
    }
    if (!conflicts.empty()) {
      std::string list;
      for (const auto& c : conflicts) list += (list.empty() ? "" : ", ") + c;
      throw Error("conflicting catalogue entries: " + list,
                  "the same shader was built with different sources, settings or seeds; rebuild the shards with one "
                  "proctex version and seed (nothing was merged)");
    }
    const int64_t id = dst.begin_build({{"command", "merge"}, {"proctex_version", kVersion}, {"inputs", [&] {
                                          std::vector<std::string> v;
                                          for (const auto& p : inputs) v.push_back(p.string());
                                          return v;
                                        }()}});
    std::map<fs::path, std::unique_ptr<Store>> open;
    for (const auto& [name, src] : chosen) {
      if (dst.summary(name)) {
        report.unchanged.push_back(name);
        continue;
      }
      auto& s = open[src.path];
      if (!s) s = std::make_unique<Store>(src.path, Store::Access::Read);
      const ShaderCatalogue cat = s->load(name);
      dst.write(cat, src.summary.device, src.summary.build_seconds, src.summary.cpu_seconds);
      report.added.push_back(name);
    }
    // Jump edges: a file's edges join two of its own shaders (foreign keys), every shader of every
    // input is now in OUT, and the conflict check proved all copies of a shader identical, so each
    // input's edges are valid in OUT as they are. Writing them never touches a pair OUT links.
    std::set<std::pair<std::string, std::string>> linked;
    for (const auto& e : dst.jumps()) linked.insert({e.shader_a, e.shader_b});
    for (const auto& p : linked) report.linked_before.push_back(p.first + "-" + p.second);
    for (const auto& in : inputs) {
      if (fs::equivalent(in, out, ec)) continue;
      auto& s = open[in];
      if (!s) s = std::make_unique<Store>(in, Store::Access::Read);
      std::map<std::pair<std::string, std::string>, std::vector<JumpEdge>> pairs;
      for (auto& e : s->jumps()) pairs[{e.shader_a, e.shader_b}].push_back(std::move(e));
      for (const auto& [pair, edges] : pairs) {
        if (!linked.insert(pair).second || !dst.summary(pair.first) || !dst.summary(pair.second)) continue;
        dst.write_jumps(pair.first, pair.second, edges);
        report.linked.push_back(pair.first + "-" + pair.second);
        report.jump_edges += static_cast<int>(edges.size());
      }
    }
    dst.finish_build(id, {{"added", report.added}, {"unchanged", report.unchanged}, {"linked", report.linked},
                          {"jump_edges", report.jump_edges}});
  } catch (...) {
    if (!existed) {
      fs::remove(out, ec);
      fs::remove(out.string() + "-wal", ec);
      fs::remove(out.string() + "-shm", ec);
    }
    throw;
  }
  return report;
}

void require_current_sources(Store& store, const ShaderLibrary& library) {
  std::string changed, list;
  for (const auto& s : store.shaders()) {
    const ShaderDecl* decl = library.find(s.name);
    if (decl && decl->source_hash != s.source_hash) {
      changed += (changed.empty() ? "" : ", ") + s.name;
      list += (list.empty() ? "" : ",") + s.name;
    }
  }
  // The command names the shaders: without --shaders a build also adds every library shader the
  // catalogue lacks. It keeps the catalogue's settings (cli/cmd_catalog.cpp), so the rebuilt
  // shaders get as many samples as the others.
  if (!changed.empty())
    throw Error("catalogue '" + store.path().string() + "' is stale: the source of " + changed +
                    " changed since it was built",
                "rebuild just those (the others are kept): proctex catalog build --db '" + store.path().string() +
                    "' --shaders " + list);
}

nlohmann::json info(const fs::path& db, const ShaderLibrary& library) {
  Store store(db, Store::Access::Read);
  nlohmann::json j = {{"db", db.string()}, {"schema_version", store.schema_version()}, {"shaders", nlohmann::json::array()}};
  std::set<std::string> present;
  for (const auto& s : store.shaders()) {
    present.insert(s.name);
    std::string stale;
    const ShaderDecl* decl = library.find(s.name);
    if (!decl) stale = "shader not in library";
    else if (decl->source_hash != s.source_hash) stale = "source changed";
    else {
      try {
        const auto& m = metrics::get_metric(s.metric);
        if (m.version() != s.metric_version) stale = "metric version changed";
      } catch (const Error&) {
        stale = "metric unknown";
      }
    }
    nlohmann::json e = {{"shader", s.name}, {"family", s.family}, {"samples", s.samples}, {"pruned", s.pruned},
                        {"mode", s.mode}, {"metric", s.metric}, {"metric_version", s.metric_version},
                        {"resolution", s.resolution}, {"seed", s.seed}, {"build_seconds", s.build_seconds},
                        {"built_at", s.built_at}, {"device", s.device}, {"proctex_version", s.proctex_version},
                        {"stale", !stale.empty()}, {"stale_reason", stale}};
    e["coverage"] = s.coverage ? s.coverage->to_json() : nlohmann::json();
    if (s.stats.contains("stop")) e["stop"] = s.stats["stop"];
    j["shaders"].push_back(e);
  }
  std::vector<std::string> missing;
  for (const auto& n : library.names())
    if (!present.count(n)) missing.push_back(n);
  j["missing"] = missing;
  j["builds"] = store.builds().size();
  return j;
}

nlohmann::json VerifyReport::to_json() const {
  return {{"ok", ok}, {"problems", problems}, {"warnings", warnings}, {"shaders", shaders}};
}

VerifyReport verify(const fs::path& db, const VerifyOptions& o, const ShaderLibrary& library) {
  VerifyReport report;
  Store store(db, Store::Access::Read);
  for (auto& p : store.integrity_problems()) report.problems.push_back(p);
  std::vector<std::string> names;
  for (const auto& s : store.shaders()) names.push_back(s.name);
  if (!o.shaders.empty()) {
    for (const auto& n : o.shaders)
      if (std::find(names.begin(), names.end(), n) == names.end())
        throw UsageError("shader '" + n + "' is not in catalogue '" + db.string() + "'", "see 'proctex catalog info'");
    names = o.shaders;
  }
  Renderer renderer(library);
  for (const auto& name : names) {
    nlohmann::json entry = {{"shader", name}};
    auto problems = store.consistency_problems(name);
    for (auto& p : problems) report.problems.push_back(p);
    entry["consistent"] = problems.empty();
    const auto sum = store.summary(name).value();
    const ShaderDecl* decl = library.find(name);
    std::string stale;
    if (!decl) stale = "not in the shader library";
    else if (decl->source_hash != sum.source_hash) stale = "source changed since the build";
    const metrics::Metric* metric = nullptr;
    try {
      metric = &metrics::get_metric(sum.metric);
      if (metric->version() != sum.metric_version) stale = "metric version changed since the build";
    } catch (const Error&) {
      stale = "metric '" + sum.metric + "' unknown";
    }
    if (!stale.empty() || !problems.empty()) {
      if (!stale.empty()) report.warnings.push_back(name + ": stale (" + stale + "), not re-rendered");
      entry["stale"] = stale;
      report.shaders.push_back(entry);
      continue;
    }
    const ShaderCatalogue cat = store.load(name, false);
    const int n = static_cast<int>(cat.samples.size());
    const int k = std::min(n, std::max(0, o.samples_per_shader));
    std::vector<int> picks;
    for (int i = 0; i < k; ++i) picks.push_back(static_cast<int>((int64_t(i) * n) / k));
    std::vector<std::vector<float>> packed;
    std::vector<uint32_t> seeds;
    for (int i : picks) {
      if (static_cast<int>(cat.samples[i].packed.size()) != decl->packed_size) {
        report.problems.push_back(name + ": sample " + std::to_string(i) + " has a packed vector of the wrong length");
        packed.clear();
        break;
      }
      packed.push_back(cat.samples[i].packed);
      seeds.push_back(cat.samples[i].seed);
    }
    double worst = 1.0;
    if (!packed.empty()) {
      RenderSettings rs;
      rs.width = rs.height = sum.resolution;
      const auto images = renderer.render_batch(*decl, packed, seeds, rs);
      for (size_t i = 0; i < images.size(); ++i) {
        const auto f = metric->features(images[i], sum.resolution);
        const double s = metric->similarity(f.values, cat.samples[picks[i]].features.values);
        worst = std::min(worst, s);
        if (s < o.min_similarity)
          report.problems.push_back(name + ": sample " + std::to_string(picks[i]) + " re-renders with similarity " +
                                    std::to_string(s) + " < " + std::to_string(o.min_similarity));
      }
    }
    entry["rerendered"] = picks.size();
    entry["min_similarity"] = worst;
    report.shaders.push_back(entry);
  }
  report.ok = report.problems.empty();
  return report;
}

Image sheet(const fs::path& db, const std::string& shader, const std::string& graph, int columns, int tile) {
  if (graph != "full" && graph != "pruned") throw UsageError("--graph must be full or pruned, got '" + graph + "'", "use --graph pruned for the small graph");
  Store store(db, Store::Access::Read);
  const ShaderCatalogue cat = store.load(shader, false);
  std::vector<int> idx;
  if (graph == "pruned") idx = cat.pruned;
  else
    for (int i = 0; i < static_cast<int>(cat.samples.size()); ++i) idx.push_back(i);
  if (idx.empty()) throw Error("shader '" + shader + "' has no samples in the " + graph + " graph", "rebuild it");
  std::vector<Image> tiles;
  std::vector<std::string> labels;
  for (int i : idx) {
    tiles.push_back(decode_png(cat.samples[i].thumbnail));
    labels.push_back("#" + std::to_string(i));
  }
  if (columns <= 0) columns = static_cast<int>(std::ceil(std::sqrt(double(tiles.size()))));
  if (tile <= 0) tile = std::max(64, tiles.front().width);
  return contact_sheet(tiles, labels, columns, tile);
}

}  // namespace proctex::catalog
