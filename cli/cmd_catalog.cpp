// proctex catalog: build, shard, merge, inspect and verify the shader catalogue.
//   proctex catalog build [--db PATH] [--shaders a,b|all] [--samples N] [--seed S] [--shard i/n] [--jobs J]
//   proctex catalog merge OUT IN...
//   proctex catalog info [--db PATH]
//   proctex catalog verify [--db PATH]
//   proctex catalog sheet SHADER -o sheet.png
#include <fmt/format.h>

#include <cstdio>
#include <memory>

#include "catalog/catalog.h"
#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "image/image.h"

namespace proctex::cli {
namespace {

namespace fs = std::filesystem;

std::string db_help() {
  return "catalogue file (default: $PROCTEX_CATALOG, else ~/.cache/proctex/catalog.sqlite; now " +
         catalog::default_catalog_path().string() + ")";
}

fs::path db_or_default(const std::string& db) { return db.empty() ? catalog::default_catalog_path() : fs::path(db); }

std::string fmt_cov(const std::optional<catalog::Coverage>& c) {
  return c ? fmt::format("{:.3f}", c->mean) : std::string("-");
}

struct BuildCli {
  std::string db, shaders = "all", shard = "1/1", mode = "adaptive", costs;
  int samples = catalog::kDefaultSamples, jobs = 0, resolution = 256, probes = -1;
  uint64_t seed = 1;
  std::vector<std::string> set;
  bool force = false, json = false;
  // Which sampling options the command line gave: only those change an existing catalogue.
  bool samples_given = false, seed_given = false, mode_given = false, resolution_given = false;
};

void run_build(const BuildCli& c, const GlobalOptions& global) {
  catalog::BuildOptions o;
  o.db = db_or_default(c.db);
  o.jobs = c.jobs;
  o.force = c.force;
  o.shard = catalog::Shard::parse(c.shard);
  o.costs = c.costs;
  // A refresh keeps the catalogue's own settings (a 48-sample catalogue stays one when a changed
  // shader is rebuilt); the options given on the command line change them.
  const auto existing = catalog::catalogue_settings(o.db);
  if (existing) {
    o.settings = existing->settings;
    o.seed = existing->seed;
  }
  if (!existing || c.seed_given) o.seed = c.seed;
  if (!existing || c.samples_given) o.settings.samples = c.samples;
  if (!existing || c.mode_given) o.settings.mode = c.mode;
  if (!existing || c.resolution_given) {
    o.settings.resolution = c.resolution;
    if (c.resolution < o.settings.screen_resolution) o.settings.screen_resolution = c.resolution;
  }
  if (c.probes >= 0) o.settings.probes = c.probes;
  if (existing && !global.quiet)
    std::fprintf(stderr, "%s: keeping its settings (%d samples, seed %llu, %s, %d probes) except those given\n",
                 o.db.string().c_str(), o.settings.samples, static_cast<unsigned long long>(o.seed),
                 o.settings.mode.c_str(), o.settings.probes);
  for (const auto& kv : c.set) {
    const auto eq = kv.find('=');
    if (eq == std::string::npos) throw UsageError("--set needs key=value, got '" + kv + "'", "e.g. --set omega=0.9");
    o.settings.apply(kv.substr(0, eq), kv.substr(eq + 1));
  }
  o.shaders = catalog::select_shaders(ShaderLibrary::builtin(), c.shaders);
  std::unique_ptr<Progress> progress;
  auto on_event = [&](const catalog::BuildEvent& e) {
    if (!progress) progress = std::make_unique<Progress>("catalog " + o.shard.str(), e.total * 100L, global.quiet);
    progress->update(e.index * 100L + static_cast<long>(e.fraction * 100), e.shader + ": " + e.stage);
  };
  const catalog::BuildReport r = catalog::build(o, on_event);
  if (progress) progress->finish();
  if (c.json) return print_json(r.to_json());
  std::vector<std::vector<std::string>> rows = {{"shader", "status", "samples", "coverage", "seconds", "note"}};
  int built = 0;
  for (const auto& s : r.shaders) {
    built += s.status != "skipped";
    std::string note = s.reason;
    if (s.stats.contains("stop")) note += ", stop: " + s.stats["stop"].get<std::string>();
    rows.push_back({s.shader, s.status, std::to_string(s.samples), fmt_cov(s.coverage),
                    s.status == "skipped" ? "-" : fmt::format("{:.2f}", s.seconds), note});
  }
  print_table(rows);
  std::printf("%s: %d built, %zu unchanged, shard %s, seed %llu, %s\n", r.db.string().c_str(), built,
              r.shaders.size() - built, r.shard.str().c_str(), static_cast<unsigned long long>(r.seed),
              format_seconds(r.seconds).c_str());
  if (r.shard.count > 1 && r.plan.is_object())
    std::printf("shard %s: planned cost %.4g of %.4g (slowest shard / mean %.3f, costs: %s)\n", r.shard.str().c_str(),
                r.plan["shards"][r.shard.index - 1]["load"].get<double>(), r.plan["total"].get<double>(),
                r.plan["balance"].get<double>(), r.plan["cost_source"].get<std::string>().c_str());
}

}  // namespace

void add_catalog_command(CLI::App& app, GlobalOptions& global) {
  CLI::App* cat = app.add_subcommand(
      "catalog",
      "The shader catalogue: samples of every shader's parameter domain (adaptive random sampling),\n"
      "their texture features and similarity graphs, in one SQLite file. Matching searches it first.");
  cat->require_subcommand(1);

  // build
  auto b = std::make_shared<BuildCli>();
  CLI::App* build = cat->add_subcommand(
      "build",
      "Build or refresh the catalogue. Incremental: a shader whose source, settings and seed are unchanged is\n"
      "skipped; an existing catalogue keeps its own settings (samples, seed, mode, resolution, probes) unless\n"
      "options change them. Each shader is written in one transaction, so a killed build loses at most the shader in\n"
      "progress; rerun to continue. --shard i/n builds every n-th shader (sorted by name) for CI jobs;\n"
      "'proctex catalog merge' joins the shard files.");
  build->add_option("--db", b->db, db_help());
  build->add_option("--shaders", b->shaders, "comma-separated shader names, or all")->capture_default_str();
  build->add_option("--samples,-n", b->samples, "samples kept per shader (N in the thesis; 48 match photos as well as 200 and build 4-5x faster)")->capture_default_str();
  build->add_option("--seed", b->seed, "seed of every random choice (same seed + sources = same samples)")->capture_default_str();
  build->add_option("--shard", b->shard, "build shard i of n (1-based), e.g. 3/8; shards are balanced by build cost")
      ->capture_default_str();
  build->add_option("--costs", b->costs,
                    "measured build costs that balance --shard: a previous catalogue or a JSON {\"shader\": seconds}\n"
                    "file, the same for every shard (default: the committed table, see 'proctex catalog plan')");
  build->add_option("--jobs,-j", b->jobs, "threads for feature extraction (0 = all cores)")->capture_default_str();
  build->add_option("--mode", b->mode, "adaptive (thesis 4.3) or uniform (baseline)")->capture_default_str();
  build->add_option("--resolution", b->resolution, "render/analysis size of stored samples")->capture_default_str();
  build->add_option("--probes", b->probes, "coverage probes P per shader (default 32; 0 = skip)");
  build->add_option("--set", b->set, "sampling setting key=value (omega, max_iterations, ...; see docs/catalog.md)")
      ->take_all();
  build->add_flag("--force", b->force, "rebuild shaders even when unchanged");
  build->add_flag("--json", b->json, "machine-readable report on stdout");
  build->callback([b, build, &global] {
    b->samples_given = build->count("--samples") > 0;
    b->seed_given = build->count("--seed") > 0;
    b->mode_given = build->count("--mode") > 0;
    b->resolution_given = build->count("--resolution") > 0;
    run_build(*b, global);
  });

  // merge
  auto merge_args = std::make_shared<std::vector<std::string>>();
  auto merge_json = std::make_shared<bool>(false);
  auto merge_opts = std::make_shared<catalog::MergeOptions>();
  CLI::App* merge = cat->add_subcommand(
      "merge", "Merge catalogue files (CI shards) into OUT (created if missing). The same shader with different\n"
               "content in two inputs is a conflict: an error, and OUT is left unchanged. Jump edges (catalog link)\n"
               "come along; a shader pair OUT already links keeps its edges.\n"
               "Refused before anything is written: inputs built with different settings, seeds, metric versions or\n"
               "shader sources (the first difference is named), and an incomplete set of shards of one --shard i/n\n"
               "build (the missing shard and its shaders are named).");
  merge->add_option("files", *merge_args, "OUT IN...")->required()->expected(2, -1);
  merge->add_flag("--json", *merge_json, "machine-readable report on stdout");
  merge->add_flag("--allow-mixed", merge_opts->allow_mixed, "merge inputs built with different settings, seeds or sources");
  merge->add_flag("--allow-partial", merge_opts->allow_partial, "merge an incomplete set of shards");
  merge->callback([merge_args, merge_json, merge_opts] {
    std::vector<fs::path> inputs(merge_args->begin() + 1, merge_args->end());
    const auto r = catalog::merge(merge_args->front(), inputs, *merge_opts);
    if (*merge_json) return print_json(r.to_json());
    std::printf("%s: %zu shaders added, %zu already present, %zu shader pairs' jump edges copied (%d edges), from %d inputs\n",
                r.out.string().c_str(), r.added.size(), r.unchanged.size(), r.linked.size(), r.jump_edges, r.inputs);
  });

  // plan
  struct PlanCli {
    std::string shaders = "all", costs;
    std::vector<int> counts = {4};
    bool json = false;
  };
  auto pc = std::make_shared<PlanCli>();
  CLI::App* plan = cat->add_subcommand(
      "plan", "Show how 'catalog build --shard i/n' splits the shaders: per shard its shaders and summed build cost,\n"
              "and the balance (slowest shard / mean; 1 is perfect). Costs: --costs (a previous catalogue's measured\n"
              "CPU seconds, or JSON) else the committed table of measured build times.");
  plan->add_option("--shards,-n", pc->counts, "shard counts n (several: one plan each)")->capture_default_str()->check(
      CLI::Range(1, 100000));
  plan->add_option("--shaders", pc->shaders, "comma-separated shader names, or all")->capture_default_str();
  plan->add_option("--costs", pc->costs, "measured costs: a catalogue or a JSON {\"shader\": seconds} file");
  plan->add_flag("--json", pc->json, "machine-readable plans on stdout");
  plan->callback([pc] {
    const auto names = catalog::select_shaders(ShaderLibrary::builtin(), pc->shaders);
    const auto costs = catalog::resolve_costs(names, pc->costs.empty() ? std::map<std::string, double>{} : catalog::read_costs(pc->costs),
                                              pc->costs);
    nlohmann::json all = nlohmann::json::array();
    for (int n : pc->counts) {
      const auto p = catalog::plan_shards(names, n, costs);
      if (pc->json) {
        all.push_back(p.to_json());
        all.back()["costs"] = costs.to_json();  // per shader: cost and where it came from
        continue;
      }
      std::vector<std::vector<std::string>> rows = {{"shard", "cost", "shaders"}};
      for (int i = 0; i < n; ++i) {
        std::string list;
        for (const auto& s : p.shards[i]) list += (list.empty() ? "" : ",") + s;
        rows.push_back({std::to_string(i + 1) + "/" + std::to_string(n), fmt::format("{:.4g}", p.load[i]), list});
      }
      print_table(rows);
      std::printf("n = %d: total %.4g, mean %.4g, slowest %.4g, balance %.3f (slowest / mean), costs: %s\n\n", n, p.total,
                  p.total / n, p.slowest(), p.balance(), p.cost_source.c_str());
    }
    if (pc->json) print_json(pc->counts.size() == 1 ? all[0] : all);
  });

  // info
  auto info_db = std::make_shared<std::string>();
  auto info_json = std::make_shared<bool>(false);
  CLI::App* info = cat->add_subcommand("info", "Per shader: samples, pruned graph size, coverage, build time, staleness.");
  info->add_option("--db", *info_db, db_help());
  info->add_flag("--json", *info_json, "machine-readable output on stdout");
  info->callback([info_db, info_json] {
    const auto j = catalog::info(db_or_default(*info_db));
    if (*info_json) return print_json(j);
    std::vector<std::vector<std::string>> rows = {
        {"shader", "samples", "pruned", "mode", "coverage", "p10", "build", "stale"}};
    for (const auto& s : j["shaders"]) {
      const bool cov = !s["coverage"].is_null();
      rows.push_back({s["shader"], std::to_string(s["samples"].get<int>()), std::to_string(s["pruned"].get<int>()),
                      s["mode"], cov ? fmt::format("{:.3f}", s["coverage"]["mean"].get<double>()) : "-",
                      cov ? fmt::format("{:.3f}", s["coverage"]["p10"].get<double>()) : "-",
                      format_seconds(s["build_seconds"].get<double>()),
                      s["stale"].get<bool>() ? s["stale_reason"].get<std::string>() : "no"});
    }
    print_table(rows);
    std::printf("%s: schema %d, %zu shaders", j["db"].get<std::string>().c_str(), j["schema_version"].get<int>(),
                j["shaders"].size());
    if (!j["missing"].empty()) std::printf(", %zu library shaders not catalogued", j["missing"].size());
    std::printf("\n");
  });

  // verify
  auto vdb = std::make_shared<std::string>();
  auto vopts = std::make_shared<catalog::VerifyOptions>();
  auto vshaders = std::make_shared<std::string>();
  auto vjson = std::make_shared<bool>(false);
  CLI::App* verify = cat->add_subcommand(
      "verify", "Check the catalogue: SQLite integrity, foreign keys, graph structure, and re-render a few samples\n"
                "per shader comparing their features with the stored ones (same device: similarity ~1).\n"
                "Exit code 1 when a check fails; stale shaders are warnings.");
  verify->add_option("--db", *vdb, db_help());
  verify->add_option("--shaders", *vshaders, "comma-separated shaders (default: all in the catalogue)");
  verify->add_option("--samples", vopts->samples_per_shader, "samples re-rendered per shader")->capture_default_str();
  verify->add_option("--min-similarity", vopts->min_similarity, "fail below this similarity")->capture_default_str();
  verify->add_flag("--json", *vjson, "machine-readable report on stdout");
  verify->callback([vdb, vopts, vshaders, vjson] {
    catalog::VerifyOptions o = *vopts;
    if (!vshaders->empty() && *vshaders != "all") {
      std::stringstream ss(*vshaders);
      for (std::string s; std::getline(ss, s, ',');)
        if (!s.empty()) o.shaders.push_back(s);
    }
    const fs::path db = db_or_default(*vdb);
    const auto r = catalog::verify(db, o);
    if (*vjson) {
      print_json(r.to_json());
    } else {
      for (const auto& w : r.warnings) std::printf("warning: %s\n", w.c_str());
      for (const auto& p : r.problems) std::printf("problem: %s\n", p.c_str());
      std::printf("%s: %s, %zu shaders checked\n", db.string().c_str(), r.ok ? "ok" : "FAILED", r.shaders.size());
    }
    if (!r.ok)
      throw Error("catalogue verification failed: " + std::to_string(r.problems.size()) + " problem(s), first: " +
                      r.problems.front(),
                  "rebuild the affected shaders with 'proctex catalog build --force --shaders ...'");
  });

  // sheet
  auto sopts = std::make_shared<std::tuple<std::string, std::string, std::string, std::string, int, int>>();
  auto& [sshader, sout, sdb, sgraph, scols, stile] = *sopts;
  sgraph = "full";
  CLI::App* sh = cat->add_subcommand("sheet", "Contact sheet of a shader's catalogue samples: the texture range at a glance.");
  sh->add_option("shader", sshader, "shader name")->required();
  sh->add_option("-o,--output", sout, "output image (PNG, JPEG, ...)")->required();
  sh->add_option("--db", sdb, db_help());
  sh->add_option("--graph", sgraph, "full or pruned")->capture_default_str();
  sh->add_option("--columns", scols, "columns (default: about square)");
  sh->add_option("--tile", stile, "tile size in pixels (default: thumbnail size, at least 64)");
  sh->callback([sopts, &global] {
    auto& [shader, out, db, graph, cols, tile] = *sopts;
    const Image img = catalog::sheet(db_or_default(db), shader, graph, cols, tile);
    save_image(img, out);
    if (!global.quiet) std::printf("%s: %dx%d\n", out.c_str(), img.width, img.height);
  });
}

}  // namespace proctex::cli
