#pragma once
// The shader catalogue (thesis section 4.3): per shader, samples of the parameter domain chosen by
// adaptive random sampling, their features, a fully connected similarity graph and a highly pruned
// second graph, in one SQLite file. Matching searches it first; morphing walks its graphs.
//
//   catalog::BuildOptions o;                      // --db, --shaders, --samples, --seed, --shard
//   o.db = catalog::default_catalog_path();
//   catalog::BuildReport r = catalog::build(o);   // incremental, resumable, one transaction per shader
//   catalog::Store store(o.db, catalog::Store::Access::Read);
//   catalog::ShaderCatalogue bricks = store.load("bricks");
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catalog/sampling.h"
#include "catalog/shard.h"
#include "catalog/store.h"
#include "image/image.h"
#include "shaders/library.h"

namespace proctex::catalog {

// Where the catalogue lives unless --db says otherwise: $PROCTEX_CATALOG if set, else
// $XDG_CACHE_HOME/proctex/catalog.sqlite, else $HOME/.cache/proctex/catalog.sqlite, else
// ./proctex-catalog.sqlite. `proctex match` and `proctex morph` read the same file.
std::filesystem::path default_catalog_path();

// CI sharding: "i/n" with 1 <= i <= n. The selected shaders are split by their build cost
// (catalog/shard.h: measured costs from --costs, else the committed table), so the slowest shard
// takes about total/n. Every shader's samples depend only on the seed, its source and the
// settings, so the shards' union equals a full build.
struct Shard {
  int index = 1;
  int count = 1;
  static Shard parse(const std::string& text);  // UsageError on a bad form
  std::string str() const { return std::to_string(index) + "/" + std::to_string(count); }
};
// The shaders of `shard`: plan_shards(names, n, resolve_costs(names, measured)).shards[i - 1].
std::vector<std::string> shard_shaders(std::vector<std::string> names, const Shard& shard,
                                       const std::map<std::string, double>& measured = {});
// "all" (or empty) -> every library shader; "a,b" -> those, checked (UsageError names close matches).
std::vector<std::string> select_shaders(const ShaderLibrary& library, const std::string& list);

struct BuildOptions {
  std::filesystem::path db;
  std::vector<std::string> shaders;  // empty: all
  SamplingSettings settings;
  uint64_t seed = 1;
  Shard shard;
  int jobs = 0;        // feature threads; 0 = hardware concurrency
  bool force = false;  // rebuild even when unchanged
  // Measured costs that balance the shards (a previous catalogue or a JSON file; read_costs()).
  // Empty: the committed table. Every shard of one build must get the same file.
  std::filesystem::path costs;
};

struct BuildEvent {
  std::string shader;
  int index = 0;  // 0-based position among the shaders this run builds
  int total = 0;
  std::string stage;
  double fraction = 0;  // within the shader
};

struct ShaderResult {
  std::string shader;
  std::string status;  // "built", "rebuilt", "skipped"
  std::string reason;  // why rebuilt / skipped
  double seconds = 0;
  int samples = 0;
  std::optional<Coverage> coverage;
  nlohmann::json stats;
};

struct BuildReport {
  std::filesystem::path db;
  Shard shard;
  uint64_t seed = 0;
  std::vector<ShaderResult> shaders;
  double seconds = 0;
  std::string device;
  nlohmann::json plan;  // ShardPlan::to_json() of the split this shard belongs to
  nlohmann::json to_json() const;
};

// The sampling settings and seed an existing catalogue was built with, when every shader in it
// agrees on them: what a refresh (`catalog build` without settings options) keeps, so that
// rebuilding the shaders whose source changed does not silently resample the others with the
// defaults. None for a missing or empty file or when the shaders disagree.
struct CatalogueSettings {
  SamplingSettings settings;
  uint64_t seed = 1;
};
std::optional<CatalogueSettings> catalogue_settings(const std::filesystem::path& db);

BuildReport build(const BuildOptions& options, const std::function<void(const BuildEvent&)>& progress = {},
                  const ShaderLibrary& library = ShaderLibrary::builtin());

struct MergeReport {
  std::filesystem::path out;
  std::vector<std::string> added, unchanged;
  // Jump edges (schema v2), per shader pair "a-b": pairs copied from an input, pairs OUT already
  // linked (kept as they are), and how many edges were copied.
  std::vector<std::string> linked, linked_before;
  int jump_edges = 0;
  int inputs = 0;
  nlohmann::json to_json() const;
};
// Copies every shader of `inputs` into `out` (created if missing). The same shader in two places
// with different content (source, settings, seed or samples) is a conflict: proctex::Error listing
// them, and `out` is left unchanged. Identical duplicates are fine (idempotent merges).
// Jump edges come along: every pair an input links is linked in `out` too (both its shaders are in
// `out` afterwards, with the content the edges were found from). A pair `out` already links keeps
// its edges; otherwise the first input (in order) that links the pair gives them.
//
// Before anything is written, the inputs (and OUT's shaders) must agree: the same seed, sampling
// settings, metric and metric version in every shader, and the same shader sources wherever two
// files know a shader (shard builds record every selected shader's source). When the inputs are
// shards of one n-shard build, all n must be there, from one plan, each with a finished build.
// Otherwise proctex::Error naming the first difference or the missing shard (and its shaders).
struct MergeOptions {
  bool allow_mixed = false;    // skip the settings / seed / metric / source agreement check
  bool allow_partial = false;  // skip the shard completeness check
};
MergeReport merge(const std::filesystem::path& out, const std::vector<std::filesystem::path>& inputs,
                  const MergeOptions& options = {});

// Throws proctex::Error naming every shader of the catalogue whose source changed since it was
// built (its stored samples are parameter vectors of another version of the shader: using them
// would silently mix versions), with the command that rebuilds just those. Shaders no longer in
// the library are ignored (match never uses them).
void require_current_sources(Store& store, const ShaderLibrary& library = ShaderLibrary::builtin());

// Per shader: samples, pruned size, coverage, build time, staleness against the current library.
nlohmann::json info(const std::filesystem::path& db, const ShaderLibrary& library = ShaderLibrary::builtin());

struct VerifyOptions {
  std::vector<std::string> shaders;  // empty: all in the catalogue
  int samples_per_shader = 2;        // re-rendered samples per shader
  double min_similarity = 0.99;      // stored vs fresh features; same device gives ~1
  int jobs = 0;
};
struct VerifyReport {
  bool ok = true;
  std::vector<std::string> problems;  // failures
  std::vector<std::string> warnings;  // stale shaders (not re-rendered)
  nlohmann::json shaders = nlohmann::json::array();
  nlohmann::json to_json() const;
};
VerifyReport verify(const std::filesystem::path& db, const VerifyOptions& options,
                    const ShaderLibrary& library = ShaderLibrary::builtin());

// Contact sheet of a shader's thumbnails; graph "full" or "pruned"; columns 0 = about square.
Image sheet(const std::filesystem::path& db, const std::string& shader, const std::string& graph = "full",
            int columns = 0, int tile = 0);

}  // namespace proctex::catalog
