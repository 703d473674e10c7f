#include "synth/graph.h"

#include <algorithm>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"

namespace proctex::synth {
namespace {

const char* kFormatHint =
    "a graph is {\"exemplars\": [\"a.png\", ...], \"edges\": [{\"from\": 0, \"to\": 1, \"scale\": 4}, ...]}; "
    "see docs/synth.md";

[[noreturn]] void bad(const std::string& name, const std::string& what, const std::string& hint = kFormatHint) {
  throw Error(fmt::format("graph '{}': {}", name, what), hint);
}

int as_index(const nlohmann::json& v, const std::string& name, const std::string& what, int count) {
  if (!v.is_number_integer()) bad(name, fmt::format("{} must be an exemplar index, got {}", what, v.dump()));
  const long long i = v.get<long long>();
  if (i < 0 || i >= count)
    bad(name, fmt::format("{} is {} but the graph has {} exemplar{} (indices 0..{})", what, i, count,
                          count == 1 ? "" : "s", count - 1),
        "exemplars are numbered from 0 (the root) in the order of \"exemplars\"");
  return static_cast<int>(i);
}

int node(int exemplar, int level, int L) { return exemplar * (L + 1) + level; }

// Out edges of every exemplar, the implicit (i, i, 0) first.
std::vector<std::vector<GraphEdge>> out_edges(const ExemplarGraph& g) {
  std::vector<std::vector<GraphEdge>> out(g.exemplars.size());
  for (size_t i = 0; i < g.exemplars.size(); ++i) out[i].push_back({static_cast<int>(i), static_cast<int>(i), 0});
  for (const auto& e : g.edges) out[e.from].push_back(e);
  return out;
}

// The closure of `start` under admissible steps (several correction passes can chain them).
std::vector<unsigned char> closure(const std::vector<std::vector<GraphEdge>>& out, int L,
                                   const std::vector<unsigned char>& start, bool finest_ok,
                                   const std::vector<unsigned char>* allowed = nullptr) {
  std::vector<unsigned char> seen(start.size(), 0);
  std::vector<int> stack;
  for (size_t n = 0; n < start.size(); ++n)
    if (start[n]) stack.push_back(static_cast<int>(n));
  while (!stack.empty()) {
    const int n = stack.back();
    stack.pop_back();
    const int i = n / (L + 1), k = n % (L + 1);
    for (const auto& e : out[i]) {
      const int l = k - e.r;
      if (l < 0 || l > L || (l == L && !finest_ok)) continue;
      const int m = node(e.to, l, L);
      if (allowed && !(*allowed)[m]) continue;
      if (!seen[m]) {
        seen[m] = 1;
        stack.push_back(m);
      }
    }
  }
  return seen;
}

}  // namespace

ExemplarGraph parse_graph_text(const std::string& text, const std::filesystem::path& base_dir,
                               const std::string& name) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    std::string msg = e.what();
    if (const auto p = msg.find("parse error"); p != std::string::npos) msg = msg.substr(p);
    bad(name, fmt::format("not valid JSON ({})", msg));
  }
  if (!j.is_object()) bad(name, "the top level must be an object");
  for (const auto& [key, value] : j.items()) {
    (void)value;
    if (key != "exemplars" && key != "edges")
      bad(name, fmt::format("unknown key '{}'", key), "the keys are \"exemplars\" and \"edges\"");
  }
  if (!j.contains("exemplars") || !j["exemplars"].is_array() || j["exemplars"].empty())
    bad(name, "\"exemplars\" must be a non-empty list of images");
  ExemplarGraph g;
  g.name = name;
  const auto& ex = j["exemplars"];
  if (ex.size() > static_cast<size_t>(kMaxGraphExemplars))
    bad(name, fmt::format("{} exemplars; at most {} are supported", ex.size(), kMaxGraphExemplars));
  for (size_t i = 0; i < ex.size(); ++i) {
    GraphExemplar e;
    std::string image;
    if (ex[i].is_string()) {
      image = ex[i].get<std::string>();
    } else if (ex[i].is_object()) {
      for (const auto& [key, value] : ex[i].items()) {
        if (key == "image" && value.is_string()) image = value.get<std::string>();
        else if (key == "tiles" && value.is_string()) e.tiles = value.get<std::string>();
        else if (key == "tiles" && value.is_boolean()) e.tiles = value.get<bool>() ? "yes" : "no";
        else
          bad(name, fmt::format("exemplar {}: unexpected \"{}\": {}", i, key, value.dump()),
              "an exemplar is \"file.png\" or {\"image\": \"file.png\", \"tiles\": \"auto\"|\"yes\"|\"no\"}");
      }
    } else {
      bad(name, fmt::format("exemplar {} must be a file name or an object, got {}", i, ex[i].dump()));
    }
    if (image.empty()) bad(name, fmt::format("exemplar {} has no \"image\"", i));
    if (e.tiles != "auto" && e.tiles != "yes" && e.tiles != "no")
      bad(name, fmt::format("exemplar {}: \"tiles\" is '{}'", i, e.tiles), "use \"auto\", \"yes\" or \"no\"");
    const std::filesystem::path p(image);
    e.image = p.is_absolute() ? p : base_dir / p;
    g.exemplars.push_back(std::move(e));
  }
  const int count = static_cast<int>(g.exemplars.size());
  if (j.contains("edges")) {
    const auto& edges = j["edges"];
    if (!edges.is_array()) bad(name, "\"edges\" must be a list");
    std::set<std::tuple<int, int, int>> seen;
    for (size_t k = 0; k < edges.size(); ++k) {
      const auto& e = edges[k];
      const std::string where = fmt::format("edge {}", k);
      if (!e.is_object())
        bad(name, fmt::format("{} must be an object {{\"from\": i, \"to\": j, \"scale\": 2^r}}, got {}", where,
                              e.dump()));
      GraphEdge edge;
      bool has_scale = false, has_r = false;
      for (const auto& [key, value] : e.items()) {
        if (key == "from") {
          edge.from = as_index(value, name, where + " \"from\"", count);
        } else if (key == "to") {
          edge.to = as_index(value, name, where + " \"to\"", count);
        } else if (key == "scale") {
          has_scale = true;
          if (!value.is_number_integer() || value.get<long long>() < 1 ||
              (value.get<long long>() & (value.get<long long>() - 1)) != 0)
            bad(name, fmt::format("{}: scale {} is not a power of two", where, value.dump()),
                "\"scale\": 4 means a pixel of \"from\" spans 4x4 pixels of \"to\" (1, 2, 4, 8, ...)");
          long long s = value.get<long long>();
          while (s > 1) s >>= 1, ++edge.r;
        } else if (key == "r") {
          has_r = true;
          if (!value.is_number_integer() || value.get<long long>() < 0 || value.get<long long>() > 30)
            bad(name, fmt::format("{}: r {} is not a small non-negative integer", where, value.dump()),
                "r is the exponent: a pixel of \"from\" spans 2^r x 2^r pixels of \"to\"");
          edge.r = static_cast<int>(value.get<long long>());
        } else {
          bad(name, fmt::format("{}: unknown key '{}'", where, key), "an edge has \"from\", \"to\" and \"scale\" (or \"r\")");
        }
      }
      if (!e.contains("from") || !e.contains("to")) bad(name, fmt::format("{} needs \"from\" and \"to\"", where));
      if (has_scale == has_r)
        bad(name, fmt::format("{} needs one of \"scale\" (a power of two) or \"r\" (its exponent)", where));
      if (edge.from == edge.to && edge.r == 0)
        bad(name, fmt::format("{} is ({}, {}, scale 1), the implicit self edge", where, edge.from, edge.to),
            "every exemplar is already similar to itself at scale 1; remove the edge");
      if (!seen.insert({edge.from, edge.to, edge.r}).second)
        bad(name, fmt::format("{} ({} -> {}, scale {}) is listed twice", where, edge.from, edge.to, 1 << edge.r));
      g.edges.push_back(edge);
    }
  }
  // Loops of scale-1 edges between different exemplars: a pixel could move around them forever at one
  // scale, its colour offset growing by the loop's offsets each time.
  std::vector<int> state(count, 0);  // 0 new, 1 on the path, 2 done
  std::vector<int> path;
  std::function<void(int)> dfs = [&](int i) {
    state[i] = 1;
    path.push_back(i);
    for (const auto& e : g.edges) {
      if (e.from != i || e.r != 0) continue;
      if (state[e.to] == 1) {
        std::string loop;
        auto it = std::find(path.begin(), path.end(), e.to);
        for (; it != path.end(); ++it) loop += std::to_string(*it) + " -> ";
        loop += std::to_string(e.to);
        bad(name, fmt::format("the scale-1 edges form a loop {} (a loop must change scale)", loop),
            "colour offsets would accumulate around it without end; remove one edge or give it a scale > 1");
      }
      if (state[e.to] == 0) dfs(e.to);
    }
    path.pop_back();
    state[i] = 2;
  };
  for (int i = 0; i < count; ++i)
    if (state[i] == 0) dfs(i);
  return g;
}

ExemplarGraph parse_graph(const std::filesystem::path& file) {
  std::ifstream f(file, std::ios::binary);
  if (!f) throw Error(fmt::format("cannot read graph '{}'", file.string()), "check the path");
  std::stringstream ss;
  ss << f.rdbuf();
  if (!f && !f.eof()) throw Error(fmt::format("cannot read graph '{}'", file.string()), "check the file");
  return parse_graph_text(ss.str(), file.parent_path(), file.string());
}

void validate_graph(const ExemplarGraph& g, int L) {
  const int max_r = std::max(0, L - 2);
  for (size_t k = 0; k < g.edges.size(); ++k) {
    const auto& e = g.edges[k];
    if (e.r > max_r)
      bad(g.name,
          fmt::format("edge {} ({} -> {}) has scale {} but these {}-level exemplars allow at most {}", k, e.from,
                      e.to, int64_t(1) << e.r, L, 1 << max_r),
          "source and destination scales must overlap: a pixel of \"from\" may span at most a quarter of \"to\"");
  }
  // Reachability from the root.
  std::vector<unsigned char> seen(g.exemplars.size(), 0);
  std::vector<int> stack{0};
  seen[0] = 1;
  while (!stack.empty()) {
    const int i = stack.back();
    stack.pop_back();
    for (const auto& e : g.edges)
      if (e.from == i && !seen[e.to]) seen[e.to] = 1, stack.push_back(e.to);
  }
  for (size_t i = 0; i < seen.size(); ++i)
    if (!seen[i])
      bad(g.name, fmt::format("exemplar {} ('{}') is not reachable from the root (exemplar 0)", i,
                              g.exemplars[i].image.filename().string()),
          "add an edge that leads to it, or remove it");
}

std::vector<StackLevel> admissible(const ExemplarGraph& g, int L, StackLevel from, bool finest_admissible) {
  std::set<StackLevel> out;
  const auto edges = out_edges(g);
  for (const auto& e : edges.at(from.exemplar)) {
    const int l = from.level - e.r;
    if (l < 0 || l > L || (l == L && !finest_admissible)) continue;
    out.insert({e.to, l});
  }
  return {out.begin(), out.end()};
}

std::vector<StackLevel> superexemplar_level(const ExemplarGraph& g, int L, int depth) {
  const auto out = out_edges(g);
  const size_t nodes = g.exemplars.size() * (L + 1);
  std::vector<unsigned char> post(nodes, 0);
  post[node(0, 0, L)] = 1;
  for (int t = 1; t <= depth; ++t) {
    std::vector<unsigned char> pre(nodes, 0);
    for (size_t n = 0; n < nodes; ++n)
      if (post[n] && static_cast<int>(n % (L + 1)) < L) pre[n + 1] = 1;
    post = closure(out, L, pre, false);
  }
  std::vector<StackLevel> result;
  for (size_t n = 0; n < nodes; ++n)
    if (post[n]) result.push_back({static_cast<int>(n / (L + 1)), static_cast<int>(n % (L + 1))});
  return result;
}

LevelSchedule level_schedule(const ExemplarGraph& g, int L, int zoom) {
  if (zoom < 0) throw UsageError("the zoom must be >= 0");
  const int T = L + zoom;
  const auto out = out_edges(g);
  const size_t nodes = g.exemplars.size() * (L + 1);
  // alive[t][n]: a pixel at node n after the correction at level t can find detail down to level T.
  std::vector<std::vector<unsigned char>> alive(T + 1, std::vector<unsigned char>(nodes, 0));
  std::fill(alive[T].begin(), alive[T].end(), 1);
  for (int t = T - 1; t >= 0; --t) {
    for (size_t n = 0; n < nodes; ++n) {
      if (static_cast<int>(n % (L + 1)) >= L) continue;
      // After upsampling to n + 1 at level t + 1, some admissible chain must reach an alive node.
      std::vector<unsigned char> start(nodes, 0);
      start[n + 1] = 1;
      const auto reach = closure(out, L, start, t + 1 == T, &alive[t + 1]);
      alive[t][n] = std::any_of(reach.begin(), reach.end(), [](unsigned char c) { return c != 0; });
    }
  }
  LevelSchedule s;
  s.levels = L;
  s.depth = T;
  s.valid.assign(T + 1, std::vector<unsigned char>(nodes, 0));
  s.valid[0][node(0, 0, L)] = alive[0][node(0, 0, L)];
  for (int t = 1; t <= T; ++t) {
    std::vector<unsigned char> pre(nodes, 0);
    for (size_t n = 0; n < nodes; ++n)
      if (s.valid[t - 1][n] && static_cast<int>(n % (L + 1)) < L) pre[n + 1] = 1;
    s.valid[t] = closure(out, L, pre, t == T, &alive[t]);
  }
  if (std::none_of(s.valid[T].begin(), s.valid[T].end(), [](unsigned char c) { return c != 0; })) {
    const int mz = max_zoom(g, L);
    throw UsageError(fmt::format("graph '{}' has no detail at zoom {}: its deepest zoom is {}", g.name, zoom, mz),
                     "add an edge to a finer exemplar (a self edge with scale 2 zooms without end), or zoom less");
  }
  return s;
}

int max_zoom(const ExemplarGraph& g, int L) {
  // Feasibility is monotone in the zoom; a reachable loop with r > 0 makes every zoom feasible,
  // and without one the depth is bounded by (exemplars) x (L + 1) levels of scale.
  auto feasible = [&](int zoom) {
    const int T = L + zoom;
    const auto out = out_edges(g);
    const size_t nodes = g.exemplars.size() * (L + 1);
    std::vector<unsigned char> alive(nodes, 1);
    for (int t = T - 1; t >= 0; --t) {
      std::vector<unsigned char> next(nodes, 0);
      for (size_t n = 0; n < nodes; ++n) {
        if (static_cast<int>(n % (L + 1)) >= L) continue;
        std::vector<unsigned char> start(nodes, 0);
        start[n + 1] = 1;
        const auto reach = closure(out, L, start, t + 1 == T, &alive);
        next[n] = std::any_of(reach.begin(), reach.end(), [](unsigned char c) { return c != 0; });
      }
      alive = std::move(next);
    }
    return alive[node(0, 0, L)] != 0;
  };
  const int bound = static_cast<int>(g.exemplars.size()) * (L + 1) + 1;
  if (!feasible(0)) throw Error(fmt::format("graph '{}': the root cannot be synthesised", g.name));
  if (feasible(bound)) return -1;
  int z = 0;
  while (z + 1 < bound && feasible(z + 1)) ++z;
  return z;
}

}  // namespace proctex::synth
