#pragma once
// Balanced catalogue shards: the selected shaders are split over n shards by their build cost, so
// that the slowest shard of n takes about total/n (shaders differ several-fold in build time).
//
//   auto costs = catalog::resolve_costs(names, catalog::read_costs("last-catalog.sqlite"));
//   catalog::ShardPlan plan = catalog::plan_shards(names, 8, costs);   // plan.shards[i - 1]
//
// Costs, in order of preference per shader: measured (a previous catalogue's recorded CPU seconds,
// or a JSON {"shader": seconds} file), else the committed table of measured build times
// (builtin_costs(), scaled to the measured unit by the median ratio over the shaders both know),
// else the median of the known costs. The plan is a pure function of (names, n, costs): every
// shard job computes the same split from the same inputs, on any machine.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace proctex::catalog {

// Build seconds per shader of the full default catalogue (adaptive, N = 200, 256 px, 2-core Xeon,
// docs/catalog.md "Adaptive vs uniform coverage"). Used when no measured costs are given.
const std::map<std::string, double>& builtin_costs();

// Measured costs from a file: a proctex catalogue (per shader CPU seconds of its build, schema v3;
// older files: the recorded build wall seconds) or a JSON object {"shader": seconds, ...}.
// proctex::Error for a missing or unreadable file.
std::map<std::string, double> read_costs(const std::filesystem::path& path);

struct ShaderCosts {
  std::map<std::string, double> cost;         // every selected shader
  std::map<std::string, std::string> origin;  // "measured", "table" or "estimate" (median)
  std::string source;                         // "built-in table" or the measured file
  nlohmann::json to_json() const;
};
ShaderCosts resolve_costs(const std::vector<std::string>& names, const std::map<std::string, double>& measured,
                          const std::string& source = {});

struct ShardPlan {
  int count = 1;
  std::vector<std::vector<std::string>> shards;  // shards[i - 1]: shader names, sorted
  std::vector<double> load;                      // summed cost per shard
  double total = 0;
  std::string cost_source;
  double slowest() const;
  double balance() const;  // slowest / (total / n): 1 is perfect
  std::string hash() const;  // of the assignment (names per shard): equal plans, equal hashes
  nlohmann::json to_json() const;
};
// Longest-processing-time-first (largest cost first, ties by name, onto the least loaded shard,
// ties to the lower index), then pairwise moves and swaps that lower the slowest shard until none
// does. Deterministic. With equal costs this is round-robin over the sorted names.
ShardPlan plan_shards(std::vector<std::string> names, int count, const ShaderCosts& costs);

}  // namespace proctex::catalog
