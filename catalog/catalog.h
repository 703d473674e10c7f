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
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "catalog/sampling.h"
#include "catalog/store.h"
#include "image/image.h"
#include "shaders/library.h"

namespace proctex::catalog {

// Where the catalogue lives unless --db says otherwise: $PROCTEX_CATALOG if set, else
// $XDG_CACHE_HOME/proctex/catalog.sqlite, else $HOME/.cache/proctex/catalog.sqlite, else
// ./proctex-catalog.sqlite. `proctex match` and `proctex morph` read the same file.
std::filesystem::path default_catalog_path();

// CI sharding: "i/n" with 1 <= i <= n. The selected shaders, sorted by name, go round-robin:
// shader at sorted position p belongs to shard (p mod n) + 1. Every shader's samples depend only on
// the seed, its source and the settings, so the shards' union equals a full build.
struct Shard {
  int index = 1;
  int count = 1;
  static Shard parse(const std::string& text);  // UsageError on a bad form
  std::string str() const { return std::to_string(index) + "/" + std::to_string(count); }
};
std::vector<std::string> shard_shaders(std::vector<std::string> names, const Shard& shard);
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
  nlohmann::json to_json() const;
};

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
MergeReport merge(const std::filesystem::path& out, const std::vector<std::filesystem::path>& inputs);

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
