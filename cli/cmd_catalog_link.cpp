// proctex catalog link: jump edges between shaders, stored in the catalogue (thesis section 5.3).
// Lives beside cmd_catalog.cpp because it needs transform/ (jump points are refined with search/).
#include <fmt/format.h>

#include <memory>
#include <sstream>

#include "catalog/catalog.h"
#include "cli/commands.h"
#include "cli/output.h"
#include "core/error.h"
#include "transform/jumps.h"

namespace proctex::cli {
namespace {

namespace fs = std::filesystem;

struct LinkCli {
  std::string db, shaders;
  transform::LinkOptions options;
  bool json = false;
};

void run(const LinkCli& c, const GlobalOptions& global) {
  const fs::path db = c.db.empty() ? catalog::default_catalog_path() : fs::path(c.db);
  if (!fs::exists(db)) throw Error("no catalogue at '" + db.string() + "'", "build one: proctex catalog build --db " + db.string());
  catalog::Store store(db, catalog::Store::Access::Write);  // migrates a v1 file (adds the jumps table)
  std::vector<std::string> names;
  if (c.shaders.empty() || c.shaders == "all") {
    for (const auto& s : store.shaders()) names.push_back(s.name);
  } else {
    std::stringstream in(c.shaders);
    for (std::string s; std::getline(in, s, ',');)
      if (!s.empty()) names.push_back(s);
  }
  for (const auto& n : names)
    if (!store.summary(n))
      throw UsageError("shader '" + n + "' is not in catalogue '" + db.string() + "'",
                       "build it first: proctex catalog build --db " + db.string() + " --shaders " + n);
  const auto pairs = transform::choose_pairs(store, names, c.options);
  Renderer renderer;
  Progress progress("link", static_cast<long>(pairs.size()), global.quiet);
  const auto r = transform::link(store, pairs, c.options, renderer, [&](const transform::LinkProgress& p) {
    progress.update(p.index, p.a + " - " + p.b);
  });
  progress.finish();
  if (c.json) {
    nlohmann::json j = r.to_json();
    j["db"] = db.string();
    return print_json(j);
  }
  std::vector<std::vector<std::string>> rows = {{"pair", "sparse best", "jump similarities", "renders", "seconds"}};
  for (const auto& p : r.pairs) {
    std::string sims;
    for (size_t k = 0; k < p.refined.size(); ++k)
      sims += fmt::format("{}{:.3f}", k ? ", " : "", p.refined[k]);
    rows.push_back({p.a + " - " + p.b, fmt::format("{:.3f}", p.sparse_best), sims, std::to_string(p.renders),
                    fmt::format("{:.1f}", p.seconds)});
  }
  print_table(rows);
  std::printf("%s: %zu pair(s) linked in %s\n", db.string().c_str(), r.pairs.size(), format_seconds(r.seconds).c_str());
}

}  // namespace

void add_catalog_link_command(CLI::App& catalog, GlobalOptions& global) {
  auto c = std::make_shared<LinkCli>();
  auto* cmd = catalog.add_subcommand(
      "link",
      "Find jump points between shaders and store them as jump edges, so 'proctex morph' can cross\n"
      "from one shader to another (thesis 5.3). Sparse samples of both shaders (their pruned graphs)\n"
      "are compared, the best pairs refined by alternating local optimisation; each pair's edges are\n"
      "replaced in one transaction. Rebuilding a shader drops its jump edges: link again.");
  cmd->footer("  proctex catalog link --shaders rectangle,superellipse,circle\n"
              "  proctex catalog link --shaders all --neighbours 3 --json");
  cmd->add_option("--db", c->db, "Catalogue (default: $PROCTEX_CATALOG or ~/.cache/proctex/catalog.sqlite)");
  cmd->add_option("--shaders", c->shaders, "Comma-separated shaders to link among, or all")->required();
  cmd->add_option("--jumps", c->options.jumps, "Jump edges kept per pair")->capture_default_str()->check(CLI::Range(1, 64));
  cmd->add_option("--neighbours", c->options.neighbours,
                  "Link each shader only to this many most similar partners (0 = every pair)")
      ->capture_default_str()->check(CLI::Range(0, 1000));
  cmd->add_option("--sparse", c->options.sparse, "Samples per shader compared (0 = its pruned graph)")->capture_default_str()->check(CLI::Range(0, 100000));
  cmd->add_option("--rounds", c->options.rounds, "Alternating optimisation rounds")->capture_default_str()->check(CLI::Range(0, 100));
  cmd->add_option("--evaluations", c->options.evaluations, "Renders per local optimisation")->capture_default_str()->check(CLI::Range(1L, 100000L));
  cmd->add_option("--resolution", c->options.resolution, "Refinement resolution (at most the catalogue's)")->capture_default_str()->check(CLI::Range(64, 4096));
  cmd->add_flag("--json", c->json, "Machine-readable report on stdout");
  cmd->callback([c, &global] { run(*c, global); });
}

}  // namespace proctex::cli
