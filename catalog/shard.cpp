#include "catalog/shard.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>

#include "catalog/store.h"
#include "core/error.h"
#include "core/hash.h"

namespace proctex::catalog {
namespace fs = std::filesystem;

const std::map<std::string, double>& builtin_costs() {
  // Adaptive build seconds, N = 200, 256 px, 32-64 probes, 2-core Xeon @ 2.10GHz, measured
  // 2026-11-22 by bench_catalog (docs/catalog.md). Only ratios matter for balancing.
  static const std::map<std::string, double> table = {
      {"burlap", 9.5},         {"knit", 7.2},          {"twill", 10.3},       {"weave", 9.7},
      {"cellular_blend", 15.7}, {"noise_stack", 16.5},  {"bricks", 8.8},       {"cobblestones", 8.5},
      {"herringbone", 13.7},   {"hextiles", 12.3},     {"pavers", 14.3},      {"stone_wall", 15.3},
      {"tiles", 15.0},         {"brushed", 16.1},      {"peeling_paint", 20.6}, {"rust", 22.3},
      {"scratches", 18.7},     {"caustics", 24.5},     {"clouds", 15.9},      {"grass", 22.7},
      {"leaves", 18.4},        {"ripples", 16.1},      {"sky", 17.0},         {"starfield", 21.8},
      {"cells", 21.7},         {"pores", 20.8},        {"scales", 13.3},      {"spots", 22.9},
      {"cardboard", 13.6},     {"crinkled", 22.2},     {"checker", 8.1},      {"chevron", 7.8},
      {"grid", 5.9},           {"polkadots", 7.6},     {"stripes", 5.9},      {"swirl", 5.9},
      {"circle", 5.9},         {"rectangle", 6.6},     {"star", 9.4},         {"superellipse", 8.5},
      {"cracked_mud", 12.7},   {"granite", 9.3},       {"gravel", 11.4},      {"marble", 11.1},
      {"sand", 8.5},           {"sandstone", 10.5},    {"slate", 11.7},       {"stones", 11.1},
      {"bark", 11.8},          {"endgrain", 9.2},      {"parquet", 9.8},      {"planks", 9.3},
      {"wood", 8.1},
  };
  return table;
}

std::map<std::string, double> read_costs(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec))
    throw Error("no cost file at '" + path.string() + "'",
                "pass a previous catalogue or a JSON {\"shader\": seconds} file to --costs, or leave --costs out");
  std::ifstream in(path, std::ios::binary);
  char magic[16] = {};
  in.read(magic, sizeof magic);
  std::map<std::string, double> out;
  if (std::string(magic, 15) == "SQLite format 3") {
    Store store(path, Store::Access::Read);
    const auto all = store.shaders();
    const bool cpu = !all.empty() && std::all_of(all.begin(), all.end(), [](const auto& s) { return s.cpu_seconds > 0; });
    for (const auto& s : all) out[s.name] = cpu ? s.cpu_seconds : s.build_seconds;
    return out;
  }
  in.clear();
  in.seekg(0);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception&) {
    throw Error("cost file '" + path.string() + "' is neither a proctex catalogue nor JSON",
                "write {\"bricks\": 8.8, \"clouds\": 15.9} or pass a catalogue");
  }
  if (!j.is_object()) throw Error("cost file '" + path.string() + "' is not a JSON object", "write {\"bricks\": 8.8}");
  for (const auto& [k, v] : j.items()) {
    if (!v.is_number() || v.get<double>() < 0)
      throw Error("cost of '" + k + "' in '" + path.string() + "' is not a non-negative number", "write seconds");
    out[k] = v.get<double>();
  }
  return out;
}

namespace {
double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}
}  // namespace

nlohmann::json ShaderCosts::to_json() const {
  nlohmann::json j = {{"source", source}, {"shaders", nlohmann::json::object()}};
  for (const auto& [name, c] : cost) j["shaders"][name] = {{"cost", c}, {"origin", origin.at(name)}};
  return j;
}

ShaderCosts resolve_costs(const std::vector<std::string>& names, const std::map<std::string, double>& measured,
                          const std::string& source) {
  ShaderCosts out;
  out.source = measured.empty() ? "built-in table" : source.empty() ? "measured" : source;
  const auto& table = builtin_costs();
  // The table's unit -> the measured unit: median ratio over the shaders both know (ratios are
  // what balancing needs; the median keeps one odd measurement from rescaling everything).
  std::vector<double> ratios;
  for (const auto& [name, c] : measured)
    if (auto t = table.find(name); t != table.end() && t->second > 0 && c > 0) ratios.push_back(c / t->second);
  const double scale = ratios.empty() ? 1.0 : median(ratios);
  std::vector<double> known;
  for (const auto& name : names) {
    if (auto m = measured.find(name); m != measured.end() && m->second > 0) {
      out.cost[name] = m->second;
      out.origin[name] = "measured";
    } else if (auto t = table.find(name); t != table.end()) {
      out.cost[name] = t->second * scale;
      out.origin[name] = "table";
    } else {
      continue;
    }
    known.push_back(out.cost[name]);
  }
  const double fallback = known.empty() ? 1.0 : median(known);
  for (const auto& name : names)
    if (!out.cost.count(name)) {
      out.cost[name] = fallback;
      out.origin[name] = "estimate";
    }
  return out;
}

double ShardPlan::slowest() const { return load.empty() ? 0.0 : *std::max_element(load.begin(), load.end()); }

double ShardPlan::balance() const { return total > 0 ? slowest() / (total / count) : 1.0; }

std::string ShardPlan::hash() const {
  std::string text;
  for (const auto& s : shards) {
    for (const auto& n : s) text += n + ",";
    text += "|";
  }
  return fnv1a_hex(text);
}

nlohmann::json ShardPlan::to_json() const {
  nlohmann::json j = {{"count", count}, {"total", total}, {"slowest", slowest()}, {"balance", balance()},
                      {"hash", hash()}, {"cost_source", cost_source}, {"shards", nlohmann::json::array()}};
  for (size_t i = 0; i < shards.size(); ++i)
    j["shards"].push_back({{"shard", std::to_string(i + 1) + "/" + std::to_string(count)}, {"load", load[i]},
                           {"shaders", shards[i]}});
  return j;
}

ShardPlan plan_shards(std::vector<std::string> names, int count, const ShaderCosts& costs) {
  if (count < 1) throw UsageError("a shard plan needs at least one shard", "use --shard i/n with n >= 1");
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  auto cost_of = [&](const std::string& n) {
    const auto it = costs.cost.find(n);
    return it == costs.cost.end() ? 1.0 : it->second;
  };
  std::vector<std::string> order = names;
  std::stable_sort(order.begin(), order.end(), [&](const auto& a, const auto& b) { return cost_of(a) > cost_of(b); });
  std::vector<std::vector<std::string>> bins(count);
  std::vector<double> load(count, 0.0);
  for (const auto& n : order) {
    const int k = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());  // first minimum
    bins[k].push_back(n);
    load[k] += cost_of(n);
  }
  // Improvement: move one shader off the slowest shard, or swap one with a cheaper one elsewhere,
  // whenever that lowers the pair's maximum; best improvement first, ties to the first found.
  auto sum = [&](const std::vector<std::string>& b) {
    double s = 0;
    for (const auto& n : b) s += cost_of(n);
    return s;
  };
  for (int round = 0; round < 10000; ++round) {
    const int h = static_cast<int>(std::max_element(load.begin(), load.end()) - load.begin());
    double best = load[h];
    int bo = -1;
    size_t bi = 0, bj = SIZE_MAX;
    for (int o = 0; o < count; ++o) {
      if (o == h) continue;
      for (size_t i = 0; i < bins[h].size(); ++i) {
        const double a = cost_of(bins[h][i]);
        const double moved = std::max(load[h] - a, load[o] + a);
        if (moved < best - 1e-9) best = moved, bo = o, bi = i, bj = SIZE_MAX;
        for (size_t j = 0; j < bins[o].size(); ++j) {
          const double b = cost_of(bins[o][j]);
          if (b >= a) continue;
          const double swapped = std::max(load[h] - a + b, load[o] + a - b);
          if (swapped < best - 1e-9) best = swapped, bo = o, bi = i, bj = j;
        }
      }
    }
    if (bo < 0) break;
    const std::string a = bins[h][bi];
    bins[h].erase(bins[h].begin() + bi);
    if (bj != SIZE_MAX) {
      bins[h].push_back(bins[bo][bj]);
      bins[bo].erase(bins[bo].begin() + bj);
    }
    bins[bo].push_back(a);
    load[h] = sum(bins[h]);
    load[bo] = sum(bins[bo]);
  }
  ShardPlan plan;
  plan.count = count;
  plan.cost_source = costs.source;
  for (auto& b : bins) std::sort(b.begin(), b.end());
  for (int k = 0; k < count; ++k) load[k] = sum(bins[k]);  // summed in name order: reproducible
  plan.shards = std::move(bins);
  plan.load = std::move(load);
  for (const auto& n : names) plan.total += cost_of(n);
  return plan;
}

}  // namespace proctex::catalog
