#include "transform/morph.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <set>

#include <fmt/format.h>

#include "core/error.h"
#include "core/version.h"
#include "metrics/metric.h"
#include "transform/jumps.h"
#include "transform/path.h"
#include "transform/space.h"

namespace proctex::transform {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Perceptual length of a step: the metric's own distance, -ln S (S = exp(-d / scale)), which adds
// up along a path where 1 - S saturates. Floored so an unreachable edge still has finite length.
double step_length(double similarity) { return -std::log(std::clamp(similarity, 1e-4, 1.0)); }

// An edge whose ends differ in a discrete parameter and in continuous coordinates by less than
// this is a pure whole step: halving cannot make it smaller.
constexpr double kPureStep = 1e-4;
// Half width (in t) of the pure whole step cut out around a discrete crossing.
constexpr double kCrossingHalfWidth = 1e-5;

// Everything plan() needs about the shaders it touches, loaded once.
class Context {
 public:
  Context(catalog::Store& store, Renderer& renderer, int jobs) : store_(store), renderer_(renderer), jobs_(jobs) {}

  const catalog::ShaderCatalogue& catalogue(const std::string& shader) {
    auto it = cats_.find(shader);
    if (it == cats_.end()) it = cats_.emplace(shader, store_.load(shader, true)).first;
    return it->second;
  }
  const MorphSpace& space(const std::string& shader) {
    auto it = spaces_.find(shader);
    if (it == spaces_.end())
      it = spaces_.emplace(shader, std::make_unique<MorphSpace>(renderer_.library().get(shader))).first;
    return *it->second;
  }
  const ShaderDecl& decl(const std::string& shader) { return renderer_.library().get(shader); }
  Renderer& renderer() { return renderer_; }

  // Perceptual length along the pixel cross-fade of two frames (frames.h dissolve_curve), cached.
  const std::vector<double>& dissolve(const TextureSpec& a, const TextureSpec& b, int resolution) {
    const std::string key = a.to_json().dump() + "|" + b.to_json().dump();
    auto it = dissolves_.find(key);
    if (it == dissolves_.end()) {
      it = dissolves_.emplace(key, dissolve_curve(a, b, renderer_, resolution, jobs_)).first;
      renders += 2;
    }
    return it->second;
  }

  // Features of many (shader, packed, seed) at `resolution`, one launch per shader.
  struct Request {
    std::string shader;
    std::vector<float> packed;
    uint32_t seed;
  };
  std::vector<metrics::Features> features(const std::vector<Request>& requests, int resolution) {
    std::map<std::string, std::vector<size_t>> by_shader;
    for (size_t i = 0; i < requests.size(); ++i) by_shader[requests[i].shader].push_back(i);
    std::vector<metrics::Features> out(requests.size());
    for (const auto& [shader, idx] : by_shader) {
      std::vector<std::vector<float>> packed;
      std::vector<uint32_t> seeds;
      for (size_t i : idx) {
        packed.push_back(requests[i].packed);
        seeds.push_back(requests[i].seed);
      }
      auto f = render_features(renderer_, decl(shader), packed, seeds, resolution, jobs_);
      for (size_t k = 0; k < idx.size(); ++k) out[idx[k]] = std::move(f[k]);
    }
    renders += static_cast<long>(requests.size());
    return out;
  }

  long renders = 0;

 private:
  catalog::Store& store_;
  Renderer& renderer_;
  int jobs_;
  std::map<std::string, catalog::ShaderCatalogue> cats_;
  std::map<std::string, std::unique_ptr<MorphSpace>> spaces_;
  std::map<std::string, std::vector<double>> dissolves_;
};

struct Key {
  TextureSpec spec;
  std::vector<float> packed;
  metrics::Features features;  // own seed, analysis resolution
};

// A vertex of the joined graph of one segment.
struct Vertex {
  std::string shader;
  std::vector<float> packed;
  const metrics::Features* features;
  std::string kind;
  int sample = -1;
};

// Shader-level adjacency from the jump edges.
std::set<std::string> component(const std::string& from, const std::vector<catalog::JumpEdge>& jumps) {
  std::set<std::string> seen = {from};
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& j : jumps) {
      const bool a = seen.count(j.shader_a), b = seen.count(j.shader_b);
      if (a != b) {
        seen.insert(a ? j.shader_b : j.shader_a);
        grew = true;
      }
    }
  }
  return seen;
}

// Dijkstra over the joined graph from key i to key i+1; the waypoints of the path (keys included).
std::vector<Waypoint> segment_path(Context& ctx, const Key& ka, const Key& kb, int ia, int ib,
                                   const std::set<std::string>& allowed, const std::vector<catalog::JumpEdge>& jumps,
                                   double power, nlohmann::json& stats) {
  const auto& metric = metrics::default_metric();
  std::vector<Vertex> v;
  std::map<std::string, std::vector<int>> members;  // vertex ids per shader
  Graph g;
  for (const auto& s : allowed) {
    const auto& cat = ctx.catalogue(s);
    const int first = static_cast<int>(v.size());
    const int n = static_cast<int>(cat.samples.size());
    for (int i = 0; i < n; ++i) {
      v.push_back({s, cat.samples[i].packed, &cat.samples[i].features, "vertex", i});
      members[s].push_back(g.add_vertex());
    }
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) g.add_edge(first + i, first + j, 1 - cat.edge(i, j));
  }
  // Jump points are vertices of their shader's graph, joined by the jump edge.
  for (const auto& j : jumps) {
    if (!allowed.count(j.shader_a) || !allowed.count(j.shader_b)) continue;
    int ends[2];
    for (int side = 0; side < 2; ++side) {
      const std::string& s = side ? j.shader_b : j.shader_a;
      const auto& packed = side ? j.packed_b : j.packed_a;
      const auto& f = side ? j.features_b : j.features_a;
      const int id = g.add_vertex();
      v.push_back({s, packed, &f, j.info.value("anchored", false) ? "anchor" : "jump", -1});
      for (int m : members[s]) g.add_edge(id, m, 1 - metric.similarity(f, *v[m].features));
      members[s].push_back(id);
      ends[side] = id;
    }
    g.add_edge(ends[0], ends[1], 1 - j.similarity);
  }
  // Keys: joined to their closest catalogue vertex (snapping), to the jump points of their shader
  // and, within one shader, to each other.
  int key_ids[2];
  int snapped[2] = {-1, -1};
  const Key* keys[2] = {&ka, &kb};
  for (int k = 0; k < 2; ++k) {
    const Key& key = *keys[k];
    const int id = g.add_vertex();
    v.push_back({key.spec.shader, key.packed, &key.features, "key", -1});
    double best = -1;
    for (int m : members[key.spec.shader]) {
      const double s = metric.similarity(key.features, *v[m].features);
      if (v[m].kind == "jump" || v[m].kind == "anchor") g.add_edge(id, m, 1 - s);
      if (v[m].kind == "vertex" && s > best) {
        best = s;
        snapped[k] = m;
      }
    }
    if (snapped[k] >= 0) g.add_edge(id, snapped[k], 1 - best);
    key_ids[k] = id;
  }
  if (ka.spec.shader == kb.spec.shader) g.add_edge(key_ids[0], key_ids[1], 1 - metric.similarity(ka.features, kb.features));

  const auto path = shortest_path(g, key_ids[0], key_ids[1], power);
  if (!path)
    throw Error("no path from shader '" + ka.spec.shader + "' to '" + kb.spec.shader + "' in the catalogue graph",
                "link them: proctex catalog link --shaders " + ka.spec.shader + "," + kb.spec.shader);
  stats.push_back({{"from", ia},
                   {"to", ib},
                   {"vertices", g.size()},
                   {"cost", path->cost},
                   {"steps", path->vertices.size() - 1},
                   {"snapped", {snapped[0] >= 0 ? v[snapped[0]].sample : -1, snapped[1] >= 0 ? v[snapped[1]].sample : -1}}});

  std::vector<Waypoint> out;
  for (size_t i = 0; i < path->vertices.size(); ++i) {
    const Vertex& x = v[path->vertices[i]];
    Waypoint w;
    w.shader = x.shader;
    w.packed = x.packed;
    w.kind = x.kind;
    w.sample = x.sample;
    if (i == 0) w.key = ia;
    if (i + 1 == path->vertices.size()) w.key = ib;
    out.push_back(std::move(w));
  }
  return out;
}

// Catalogue samples and jump points hold the declared defaults for parameters the catalogue does
// not vary (fixed ones); along a path they follow the keys instead: interpolated between two keys
// of the same shader, else copied from the key in that shader.
void carry_fixed_parameters(Context& ctx, std::vector<Waypoint>& seg, const Key& ka, const Key& kb) {
  const size_t n = seg.size();
  for (size_t i = 1; i + 1 < n; ++i) {
    Waypoint& w = seg[i];
    const MorphSpace& sp = ctx.space(w.shader);
    if (w.shader == ka.spec.shader && w.shader == kb.spec.shader)
      w.packed = sp.with_fixed_from(w.packed, sp.lerp(ka.packed, kb.packed, double(i) / double(n - 1)));
    else if (w.shader == ka.spec.shader)
      w.packed = sp.with_fixed_from(w.packed, ka.packed);
    else if (w.shader == kb.spec.shader)
      w.packed = sp.with_fixed_from(w.packed, kb.packed);
  }
}

std::string discrete_note(const ShaderDecl& decl, const std::vector<float>& a, const std::vector<float>& b) {
  for (const auto& p : decl.params)
    if (p.discrete() && a[p.offset] != b[p.offset]) return "whole step of " + p.name;
  return "whole step";
}

// Adaptive linear subdivision (thesis 5.2), breadth first so each round is one launch per shader;
// the least similar edges go first when the render budget runs out.
void subdivide(Context& ctx, std::vector<Waypoint>& path, const MorphOptions& o, uint32_t seed, int resolution,
               const std::function<void(double)>& progress) {
  const auto& metric = metrics::default_metric();
  long budget = o.max_renders;
  for (int round = 0;; ++round) {
    std::vector<size_t> split;
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      Waypoint& w = path[i];
      if (w.jump || !w.note.empty()) continue;
      const MorphSpace& sp = ctx.space(w.shader);
      const int step = sp.max_discrete_step(w.packed, path[i + 1].packed);
      if (w.similarity >= o.threshold && step <= 1) continue;
      if (w.depth >= o.max_depth) {
        w.note = "depth cap";
        continue;
      }
      if (step <= 1 && sp.max_continuous_difference(w.packed, path[i + 1].packed) < kPureStep) {
        w.note = discrete_note(sp.decl(), w.packed, path[i + 1].packed);
        continue;
      }
      split.push_back(i);
    }
    if (split.empty()) break;
    std::stable_sort(split.begin(), split.end(), [&](size_t a, size_t b) { return path[a].similarity < path[b].similarity; });
    if (static_cast<long>(split.size()) > budget) {
      for (size_t k = budget; k < split.size(); ++k) path[split[k]].note = "render budget";
      split.resize(budget);
    }
    if (split.empty()) break;
    std::sort(split.begin(), split.end());
    // An edge where a discrete parameter changes is cut just before and just after the change,
    // so the whole step stands alone (a pure step, kPureStep) and the rest halves as usual;
    // other edges are halved at their midpoint.
    std::vector<Context::Request> req;
    std::vector<std::vector<std::vector<float>>> inserts(split.size());
    std::vector<bool> edge_crossed(split.size());
    for (size_t k = 0; k < split.size(); ++k) {
      const size_t i = split[k];
      const MorphSpace& sp = ctx.space(path[i].shader);
      const auto crossings = sp.discrete_crossings(path[i].packed, path[i + 1].packed);
      double previous = 0;
      for (size_t c = 0; c < crossings.size(); ++c) {
        const double t = crossings[c], next = c + 1 < crossings.size() ? crossings[c + 1] : 1.0;
        const double before = std::max(t - kCrossingHalfWidth, (previous + t) / 2);
        const double after = std::min(t + kCrossingHalfWidth, (t + next) / 2);
        if (before > previous) inserts[k].push_back(sp.lerp(path[i].packed, path[i + 1].packed, before));
        inserts[k].push_back(sp.lerp(path[i].packed, path[i + 1].packed, after));
        previous = after;
      }
      if (crossings.empty()) inserts[k].push_back(sp.lerp(path[i].packed, path[i + 1].packed, 0.5));
      edge_crossed[k] = !crossings.empty();
      for (const auto& p : inserts[k]) req.push_back({path[i].shader, p, seed});
    }
    auto feats = ctx.features(req, resolution);
    budget -= static_cast<long>(req.size());
    std::vector<Waypoint> next;
    size_t k = 0, f = 0;
    for (size_t i = 0; i < path.size(); ++i) {
      next.push_back(path[i]);
      if (k < split.size() && split[k] == i) {
        // Cutting out whole steps is not a halving: it does not count towards the depth cap.
        const int depth = path[i].depth + (edge_crossed[k] ? 0 : 1);
        next.back().depth = depth;
        for (auto& p : inserts[k]) {
          Waypoint mid;
          mid.shader = path[i].shader;
          mid.packed = std::move(p);
          mid.kind = "subdivision";
          mid.features = std::move(feats[f++]);
          mid.depth = depth;
          next.back().similarity = metric.similarity(next.back().features, mid.features);
          next.push_back(std::move(mid));
        }
        next.back().similarity = metric.similarity(next.back().features, path[i + 1].features);
        ++k;
      }
    }
    path = std::move(next);
    if (progress) progress(1.0 - double(budget) / std::max(1, o.max_renders));
  }
  for (size_t i = 0; i < path.size(); ++i) {
    Waypoint& w = path[i];
    w.reached = w.jump || w.similarity >= o.threshold;
    if (w.reached) {
      w.note.clear();
    } else if (i + 1 < path.size() && ctx.space(w.shader).max_discrete_step(w.packed, path[i + 1].packed) > 0) {
      // Halving cannot remove a whole step; name the parameter rather than blaming the depth cap.
      w.note = discrete_note(ctx.space(w.shader).decl(), w.packed, path[i + 1].packed) +
               (w.note == "render budget" ? " (render budget)" : "");
    } else if (w.note.empty()) {
      w.note = "depth cap";
    }
  }
}

// Largest-remainder shares of `total` proportional to `weights` (equal shares when all are 0).
std::vector<int> apportion(const std::vector<double>& weights, int total) {
  std::vector<int> out(weights.size(), 0);
  if (weights.empty() || total <= 0) return out;
  double sum = 0;
  for (double w : weights) sum += w;
  std::vector<double> w = weights;
  if (sum <= 0) {
    std::fill(w.begin(), w.end(), 1.0);
    sum = static_cast<double>(w.size());
  }
  std::vector<std::pair<double, size_t>> rest;
  int given = 0;
  for (size_t i = 0; i < w.size(); ++i) {
    const double exact = total * w[i] / sum;
    out[i] = static_cast<int>(std::floor(exact));
    given += out[i];
    rest.emplace_back(exact - out[i], i);
  }
  std::sort(rest.begin(), rest.end(), [](auto& a, auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
  for (size_t k = 0; given < total; ++k, ++given) ++out[rest[k % rest.size()].second];
  return out;
}

// `total` steps over units of perceptual `lengths`, each at least `minimum` (sum <= total): units
// whose proportional share falls below their minimum get the minimum, the others share the rest
// in proportion to their length - so steps are as equal in perceptual length as the minimums
// allow. Units of weight 0 (whole steps) keep their minimum.
std::vector<int> allocate(const std::vector<double>& lengths, const std::vector<int>& minimum, int total) {
  const size_t n = lengths.size();
  std::vector<bool> pinned(n);
  for (size_t i = 0; i < n; ++i) pinned[i] = lengths[i] <= 0;
  int rest = total;
  for (bool changed = true; changed;) {
    changed = false;
    double sum = 0;
    rest = total;
    for (size_t i = 0; i < n; ++i) {
      if (pinned[i]) rest -= minimum[i];
      else sum += lengths[i];
    }
    for (size_t i = 0; i < n; ++i)
      if (!pinned[i] && rest * lengths[i] / sum < minimum[i]) pinned[i] = changed = true;
  }
  // A free unit's share is at least its (whole) minimum, so its floor is too.
  std::vector<double> w(n, 0.0);
  bool any_free = false;
  for (size_t i = 0; i < n; ++i) {
    w[i] = pinned[i] ? 0.0 : lengths[i];
    any_free |= !pinned[i];
  }
  std::vector<int> out = minimum;
  if (!any_free) {  // every unit at its minimum: the steps left go by length to those that have one
    for (size_t i = 0; i < n; ++i) w[i] = std::max(0.0, lengths[i]);
    const auto extra = apportion(w, rest);
    for (size_t i = 0; i < n; ++i) out[i] += extra[i];
    return out;
  }
  const auto share = apportion(w, rest);
  for (size_t i = 0; i < n; ++i)
    if (!pinned[i]) out[i] = share[i];
  return out;
}

// The spec waypoint i renders as a frame of its own: a key's exact input (its own seed), else the
// waypoint at the path's seed.
TextureSpec waypoint_spec(Context& ctx, const Waypoint& w, const std::vector<Key>& keys, uint32_t seed) {
  if (w.key >= 0) return spec_from_packed(ctx.decl(w.shader), keys[w.key].packed, keys[w.key].spec.seed);
  return spec_from_packed(ctx.decl(w.shader), w.packed, seed);
}

// Perceptual length of the edge from waypoint i to i + 1 as the frames will cross it: a jump is
// crossed by a dissolve (the measured length of the cross-fade), any other edge by interpolation.
double edge_length(Context& ctx, const std::vector<Waypoint>& path, size_t i, const std::vector<Key>& keys,
                   uint32_t seed, int resolution, int dissolve) {
  if (!path[i].jump || dissolve <= 0) return step_length(path[i].similarity);
  return ctx.dissolve(waypoint_spec(ctx, path[i], keys, seed), waypoint_spec(ctx, path[i + 1], keys, seed), resolution).back();
}

// Between keys in two shaders that catalog link joined directly, a dissolve of the keys themselves
// is a route too. It replaces the refined route when its measured perceptual length is shorter:
// frames are spread evenly in perceptual length, so the shorter route has the smaller steps. (With
// the default metric a cross-fade of two flat shapes is shorter than any shape change: docs/morph.md.)
void prefer_shorter_dissolves(Context& ctx, std::vector<Waypoint>& path, const std::vector<Key>& keys,
                              const std::set<std::pair<std::string, std::string>>& linked, uint32_t seed,
                              int resolution, int dissolve, nlohmann::json& segments) {
  const auto& metric = metrics::default_metric();
  std::vector<size_t> at;  // waypoint index of each key
  for (size_t i = 0; i < path.size(); ++i)
    if (path[i].key >= 0) at.push_back(i);
  std::vector<Waypoint> out;
  for (size_t k = 0; k + 1 < at.size(); ++k) {
    const size_t a = at[k], b = at[k + 1];
    if (k == 0) out.push_back(path[a]);
    const std::string& sa = path[a].shader;
    const std::string& sb = path[b].shader;
    const bool candidate = dissolve > 0 && sa != sb && linked.count({std::min(sa, sb), std::max(sa, sb)});
    double route = 0, direct = 0;
    if (candidate) {
      for (size_t i = a; i < b; ++i) route += edge_length(ctx, path, i, keys, seed, resolution, dissolve);
      direct = ctx.dissolve(waypoint_spec(ctx, path[a], keys, seed), waypoint_spec(ctx, path[b], keys, seed), resolution).back();
      segments[k]["route_length"] = route;
      segments[k]["dissolve_length"] = direct;
    }
    if (candidate && direct < route) {
      out.back().jump = true;
      out.back().reached = true;
      out.back().note.clear();
      out.back().similarity = metric.similarity(path[a].features, path[b].features);
      segments[k]["route"] = "dissolve of the keys";
    } else {
      for (size_t i = a + 1; i < b; ++i) out.push_back(path[i]);
      if (candidate) segments[k]["route"] = "path";
    }
    out.push_back(path[b]);
  }
  path = std::move(out);
}

// Frames from the refined path. The path is cut into units: atoms, which one frame step must
// cross whole (a jump edge, plus its dissolve frames; a pure whole step of a discrete parameter),
// and continuous stretches between atoms and keys. Every unit gets its minimum (one step, or
// dissolve + 1 for a jump); the remaining steps go to the stretches in proportion to their
// perceptual length, and frames sit at equal perceptual distances within each stretch. So each
// frame changes about the same amount, and a whole step never shares a frame step with other
// change. When the frames are too few for that, whole steps are treated as continuous again.
std::vector<Frame> resample(Context& ctx, const std::vector<Waypoint>& path, const std::vector<Key>& keys, int frames,
                            int dissolve, bool blend_steps, uint32_t seed, int resolution) {
  struct Unit {
    bool atom = false, jump = false;
    size_t first = 0, last = 0;  // waypoints: the unit spans edges first .. last-1
    double length = 0;
    int steps = 0;
  };
  auto is_step_atom = [&](size_t i) {
    const MorphSpace& sp = ctx.space(path[i].shader);
    return sp.max_discrete_step(path[i].packed, path[i + 1].packed) > 0 &&
           sp.max_continuous_difference(path[i].packed, path[i + 1].packed) < kPureStep;
  };
  auto build_units = [&](bool step_atoms) {
    std::vector<Unit> units;
    size_t start = 0;
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      const bool atom = path[i].jump || (step_atoms && is_step_atom(i));
      if (atom) {
        if (i > start) units.push_back({false, false, start, i, 0, 1});
        units.push_back({true, path[i].jump, i, i + 1, 0, path[i].jump ? dissolve + 1 : 1});
        start = i + 1;
      } else if (path[i + 1].key >= 0) {  // keys are frames: a stretch ends there
        units.push_back({false, false, start, i + 1, 0, 1});
        start = i + 1;
      }
    }
    for (auto& u : units)
      for (size_t i = u.first; i < u.last; ++i) u.length += edge_length(ctx, path, i, keys, seed, resolution, dissolve);
    return units;
  };
  auto required = [](const std::vector<Unit>& units) {
    int n = 0;
    for (const auto& u : units) n += u.steps;
    return n;
  };
  std::vector<Unit> units = build_units(true);
  if (required(units) > frames - 1) units = build_units(false);
  const int need = required(units) + 1;
  if (frames < need) {
    int jumps = 0;
    for (const auto& u : units) jumps += u.jump;
    throw UsageError(fmt::format("--frames {} is too few for this morph: it needs at least {} (inputs, both ends of "
                                 "{} jump(s){})", frames, need, jumps, dissolve ? ", dissolve frames" : ""),
                     fmt::format("use --frames {} or more", need));
  }
  // Stretches and dissolves share the steps by perceptual length (a dissolve gets at least its
  // --dissolve frames); whole steps and hard cuts take one step each.
  std::vector<double> weights;
  std::vector<int> minimum;
  bool any_stretch = false;
  for (const auto& u : units) {
    const bool shares = !u.atom || (u.jump && dissolve > 0);
    weights.push_back(shares ? u.length : 0.0);
    minimum.push_back(u.steps);
    any_stretch |= shares;
  }
  if (!any_stretch && frames > need)
    throw UsageError(fmt::format("this morph is {} frames of jumps; --frames {} leaves frames with nothing to show", need, frames),
                     fmt::format("use --frames {} or a --dissolve", need));
  double sum = 0;
  for (double w : weights) sum += w;
  if (sum <= 0)  // every stretch has length 0 (identical keys): equal shares
    for (size_t k = 0; k < units.size(); ++k) weights[k] = units[k].atom && !(units[k].jump && dissolve > 0) ? 0.0 : 1.0;
  const auto steps = allocate(weights, minimum, frames - 1);
  for (size_t k = 0; k < units.size(); ++k) units[k].steps = steps[k];
  double total_length = 0;
  for (const auto& u : units) total_length += u.length;
  auto norm = [&](double p) { return total_length > 0 ? p / total_length : 0.0; };

  auto frame_at = [&](size_t i, double t, double position) {
    Frame f;
    const Waypoint& w = path[i];
    const MorphSpace& sp = ctx.space(w.shader);
    f.position = norm(position);
    if (t <= 0 && w.key >= 0) {  // exactly the input, its own seed
      f.spec = spec_from_packed(sp.decl(), keys[w.key].packed, keys[w.key].spec.seed);
      f.key = w.key;
      return f;
    }
    if (t > 0 && blend_steps && sp.max_discrete_step(w.packed, path[i + 1].packed) > 0) {
      // A whole step of a discrete parameter cannot be interpolated: the frames inside it
      // cross-fade the renders of its two ends (each at whole values) instead of popping.
      f.spec = spec_from_packed(sp.decl(), w.packed, seed);
      f.blend_to = spec_from_packed(sp.decl(), path[i + 1].packed, seed);
      f.blend = t;
      return f;
    }
    std::vector<float> packed = t <= 0 ? w.packed : sp.lerp(w.packed, path[i + 1].packed, t);
    f.spec = spec_from_packed(sp.decl(), packed, seed);
    return f;
  };

  std::vector<Frame> out;
  out.push_back(frame_at(0, 0, 0));
  double position = 0;
  for (const auto& u : units) {
    if (u.atom) {
      const Frame from = out.back();
      const Frame to = frame_at(u.last, 0, position + u.length);
      // Dissolve frames at equal perceptual distances along the cross-fade of the jump's ends.
      const auto blends = u.steps > 1 ? dissolve_blends(ctx.dissolve(from.spec, to.spec, resolution), u.steps - 1)
                                      : std::vector<double>();
      for (int d = 1; d < u.steps; ++d) {  // dissolve frames
        Frame f = from;
        f.key = -1;
        f.blend_to = to.spec;
        f.blend = blends[d - 1];
        f.jump = d == 1;
        f.position = norm(position + u.length * f.blend);
        out.push_back(std::move(f));
      }
      out.push_back(to);
      out.back().jump = u.jump && u.steps == 1;
      position += u.length;
      continue;
    }
    // Interior frames at equal perceptual distances along the stretch.
    size_t i = u.first;
    double walked = 0;  // perceptual length from u.first to waypoint i
    for (int j = 1; j < u.steps; ++j) {
      const double target = u.length * j / u.steps;
      while (i + 1 < u.last && walked + step_length(path[i].similarity) < target) walked += step_length(path[i++].similarity);
      const double len = step_length(path[i].similarity);
      const double t = len > 0 ? std::clamp((target - walked) / len, 0.0, 1.0) : 0.5;
      out.push_back(t >= 1 ? frame_at(i + 1, 0, position + target) : frame_at(i, t, position + target));
    }
    position += u.length;
    out.push_back(frame_at(u.last, 0, position));
  }
  return out;
}

}  // namespace

nlohmann::json Waypoint::to_json() const {
  nlohmann::json j = {{"shader", shader}, {"kind", kind}};
  if (key >= 0) j["key"] = key;
  if (sample >= 0) j["sample"] = sample;
  j["similarity_to_next"] = similarity;
  if (jump) j["jump"] = true;
  if (!reached) j["unreached"] = note;
  return j;
}

int Morph::unreached_count() const {
  int n = 0;
  for (size_t i = 0; i + 1 < path.size(); ++i) n += !path[i].reached;
  return n;
}

nlohmann::json Morph::unreached() const {
  nlohmann::json out = nlohmann::json::array();
  for (size_t i = 0; i + 1 < path.size(); ++i)
    if (!path[i].reached)
      out.push_back({{"shader", path[i].shader}, {"from", i}, {"to", i + 1}, {"similarity", path[i].similarity},
                     {"reason", path[i].note}});
  return out;
}

nlohmann::json Morph::quality_json() const {
  nlohmann::json q = nlohmann::json::object();
  if (quality) q["morph"] = quality->to_json();
  if (linear) q["linear"] = linear->to_json();
  if (quality && linear) {
    q["beats_linear_on_max"] = quality->max_dissimilarity < linear->max_dissimilarity;
    q["beats_linear_on_mean"] = quality->mean_dissimilarity < linear->mean_dissimilarity;
  }
  return q;
}

nlohmann::json Morph::summary() const {
  nlohmann::json in = nlohmann::json::array();
  for (const auto& s : inputs) in.push_back(s.to_json());
  return {{"proctex_version", kVersion},
          {"inputs", in},
          {"frames", frames.size()},
          {"shaders", shaders},
          {"jumps", jumps},
          {"seed", seed},
          {"resolution", resolution},
          {"options",
           {{"frames", options.frames}, {"power", options.power}, {"threshold", options.threshold},
            {"max_depth", options.max_depth}, {"max_renders", options.max_renders}, {"dissolve", options.dissolve},
            {"connective", options.connective}, {"blend_steps", options.blend_steps}}},
          {"waypoints", path.size()},
          {"unreached", unreached()},
          {"quality", quality_json()},
          {"warnings", warnings},
          {"stats", stats}};
}

nlohmann::json Morph::manifest() const {
  nlohmann::json j = summary();
  j["frames"] = nlohmann::json::array();
  for (size_t i = 0; i < frames.size(); ++i) {
    nlohmann::json f = frames[i].to_json();
    f["index"] = i;
    j["frames"].push_back(std::move(f));
  }
  j["path"] = nlohmann::json::array();
  for (const auto& w : path) j["path"].push_back(w.to_json());
  return j;
}

Morph plan(const std::vector<TextureSpec>& inputs, catalog::Store& store, Renderer& renderer, const MorphOptions& o,
           const std::function<void(const MorphProgress&)>& progress) {
  const auto t0 = Clock::now();
  auto report = [&](const std::string& stage, double f) {
    if (progress) progress({stage, f});
  };
  if (inputs.size() < 2) throw UsageError("a morph needs at least two textures", "e.g. proctex morph a.json b.json");
  if (o.frames < static_cast<int>(inputs.size()))
    throw UsageError(fmt::format("--frames {} is fewer than the {} textures given", o.frames, inputs.size()));
  if (o.threshold <= 0 || o.threshold >= 1) throw UsageError("--threshold must be in (0, 1)");
  if (o.power < 1) throw UsageError("--power must be at least 1", "the thesis uses n = 1, 2, 3");
  if (o.max_depth < 0 || o.max_renders < 0 || o.dissolve < 0) throw UsageError("--depth, --max-renders and --dissolve cannot be negative");

  const auto& metric = metrics::default_metric();
  Context ctx(store, renderer, o.jobs);
  Morph m;
  m.inputs = inputs;
  m.options = o;
  m.seed = inputs.front().seed;

  // Keys: checked against their declarations and the catalogue.
  std::vector<Key> keys;
  for (const auto& spec : inputs) {
    const ShaderDecl& decl = renderer.library().get(spec.shader);
    const auto sum = store.summary(spec.shader);
    if (!sum)
      throw Error("shader '" + spec.shader + "' is not in catalogue '" + store.path().string() + "'",
                  "build it: proctex catalog build --db " + store.path().string() + " --shaders " + spec.shader);
    if (sum->metric != metric.id() || sum->metric_version != metric.version())
      throw Error("catalogue shader '" + spec.shader + "' has " + sum->metric + " v" + std::to_string(sum->metric_version) +
                      " features, this proctex computes " + metric.id() + " v" + std::to_string(metric.version()),
                  "rebuild it: proctex catalog build --shaders " + spec.shader);
    if (m.resolution == 0) m.resolution = sum->resolution;
    if (sum->resolution != m.resolution)
      throw Error("catalogue shaders '" + inputs.front().shader + "' and '" + spec.shader + "' were built at different resolutions",
                  "rebuild them with one --resolution");
    keys.push_back({spec, resolve(decl, spec), {}});
    if (spec.seed != m.seed)
      m.warnings.push_back(fmt::format("input {} has seed {} but the path keeps seed {}: its own frame changes layout",
                                       keys.size() - 1, spec.seed, m.seed));
  }
  report("keys", 0);
  {
    std::vector<Context::Request> req;
    for (const auto& k : keys) req.push_back({k.spec.shader, k.packed, k.spec.seed});
    auto f = ctx.features(req, m.resolution);
    for (size_t i = 0; i < keys.size(); ++i) keys[i].features = std::move(f[i]);
  }

  // Jump edges usable with the current metric; stale ones are skipped with a warning.
  std::vector<catalog::JumpEdge> jumps;
  int stale = 0;
  for (auto& j : store.jumps()) {
    if (j.features_a.metric == metric.id() && j.features_a.version == metric.version() &&
        j.features_a.resolution == m.resolution)
      jumps.push_back(std::move(j));
    else
      ++stale;
  }
  if (stale) m.warnings.push_back(fmt::format("{} jump edge(s) from another metric or resolution ignored (rerun catalog link)", stale));

  // One path per pair of consecutive keys.
  report("path", 0);
  const auto t_path = Clock::now();
  nlohmann::json segments = nlohmann::json::array(), anchors = nlohmann::json::array();
  long anchor_renders = 0;
  for (size_t i = 0; i + 1 < keys.size(); ++i) {
    const std::string& sa = keys[i].spec.shader;
    const std::string& sb = keys[i + 1].spec.shader;
    std::set<std::string> allowed = {sa};
    if (sa != sb) {
      const auto reach = component(sa, jumps);
      if (!reach.count(sb))
        throw Error("no jump edges connect shader '" + sa + "' to '" + sb + "' in catalogue '" + store.path().string() + "'",
                    "link them first: proctex catalog link --shaders " + sa + "," + sb +
                        " (or through a connective shader: --shaders " + sa + ",OTHER," + sb + ")");
      allowed = o.connective ? reach : std::set<std::string>{sa, sb};
      if (!o.connective) {
        const bool direct = std::any_of(jumps.begin(), jumps.end(), [&](const auto& j) {
          return (j.shader_a == sa && j.shader_b == sb) || (j.shader_a == sb && j.shader_b == sa);
        });
        if (!direct)
          throw Error("no jump edge joins '" + sa + "' and '" + sb + "' directly", "allow connective shaders, or link the pair");
      }
    }
    std::vector<catalog::JumpEdge> seg_jumps = jumps;
    if (sa != sb && o.anchor) {
      // Anchored jumps: each key into every allowed shader catalog link joined to its shader.
      // Non-searchable parameters of the point come from the segment's key in that shader.
      AnchorOptions ao;
      ao.evaluations = o.anchor_evaluations;
      for (size_t k : {i, i + 1}) {
        const Key& key = keys[k];
        std::set<std::string> partners;
        for (const auto& j : jumps) {
          if (j.shader_a == key.spec.shader && allowed.count(j.shader_b)) partners.insert(j.shader_b);
          if (j.shader_b == key.spec.shader && allowed.count(j.shader_a)) partners.insert(j.shader_a);
        }
        for (const auto& t : partners) {
          const Key& other = keys[k == i ? i + 1 : i];
          const auto base = other.spec.shader == t ? other.packed : ctx.decl(t).default_packed();
          const auto ta = Clock::now();
          auto e = anchor_jump(key.spec.shader, key.packed, key.spec.seed, key.features, ctx.catalogue(t), base, m.seed,
                               renderer, ao);
          anchors.push_back({{"key", k}, {"shader", t}, {"similarity", e.similarity}, {"seconds", seconds_since(ta)},
                             {"info", e.info}});
          anchor_renders += e.info.value("evaluations", 0L) + 3;
          seg_jumps.push_back(std::move(e));
        }
      }
    }
    auto seg = segment_path(ctx, keys[i], keys[i + 1], static_cast<int>(i), static_cast<int>(i + 1), allowed, seg_jumps,
                            o.power, segments);
    carry_fixed_parameters(ctx, seg, keys[i], keys[i + 1]);
    if (!m.path.empty()) m.path.pop_back();  // the key shared with the previous segment
    for (auto& w : seg) {
      // Drop a vertex identical to its predecessor (a key that is itself a catalogue sample).
      if (!m.path.empty() && m.path.back().shader == w.shader && m.path.back().packed == w.packed && w.key < 0) continue;
      if (!m.path.empty() && m.path.back().shader == w.shader && m.path.back().packed == w.packed && m.path.back().key < 0) m.path.pop_back();
      m.path.push_back(std::move(w));
    }
    report("path", double(i + 1) / (keys.size() - 1));
  }
  for (size_t i = 0; i + 1 < m.path.size(); ++i) m.path[i].jump = m.path[i].shader != m.path[i + 1].shader;

  // Every waypoint at the path's seed (spatial coherence), then the similarity of each edge.
  {
    std::vector<Context::Request> req;
    for (const auto& w : m.path) req.push_back({w.shader, w.packed, m.seed});
    auto f = ctx.features(req, m.resolution);
    for (size_t i = 0; i < m.path.size(); ++i) m.path[i].features = std::move(f[i]);
    for (size_t i = 0; i + 1 < m.path.size(); ++i)
      m.path[i].similarity = metric.similarity(m.path[i].features, m.path[i + 1].features);
  }
  const double path_seconds = seconds_since(t_path);
  const long path_renders = ctx.renders;
  const size_t graph_waypoints = m.path.size();

  report("subdivide", 0);
  const auto t_sub = Clock::now();
  subdivide(ctx, m.path, o, m.seed, m.resolution, [&](double f) { report("subdivide", f); });
  if (o.anchor) {
    std::set<std::pair<std::string, std::string>> linked;
    for (const auto& j : jumps) linked.insert({std::min(j.shader_a, j.shader_b), std::max(j.shader_a, j.shader_b)});
    prefer_shorter_dissolves(ctx, m.path, keys, linked, m.seed, m.resolution, o.dissolve, segments);
  }
  for (const auto& w : m.path) {
    if (m.shaders.empty() || m.shaders.back() != w.shader) m.shaders.push_back(w.shader);
    m.jumps += w.jump;
  }
  report("frames", 0);
  m.frames = resample(ctx, m.path, keys, o.frames, o.dissolve, o.blend_steps, m.seed, m.resolution);
  m.stats = {{"segments", segments},
             {"graph_waypoints", graph_waypoints},
             {"anchors", anchors},
             {"renders", {{"keys_and_path", path_renders}, {"anchors", anchor_renders}, {"subdivision", ctx.renders - path_renders}}},
             {"seconds", {{"path", path_seconds}, {"subdivision", seconds_since(t_sub)}, {"plan", seconds_since(t0)}}}};
  return m;
}

std::vector<Frame> linear_frames(const std::vector<TextureSpec>& inputs, int frames, const ShaderLibrary& library) {
  if (inputs.size() < 2 || frames < static_cast<int>(inputs.size()))
    throw UsageError("linear interpolation needs at least two inputs and as many frames");
  const uint32_t seed = inputs.front().seed;
  const int keys = static_cast<int>(inputs.size());
  std::vector<Frame> out;
  for (int k = 0; k + 1 < keys; ++k) {
    const int fa = static_cast<int>(std::lround(double(k) * (frames - 1) / (keys - 1)));
    const int fb = static_cast<int>(std::lround(double(k + 1) * (frames - 1) / (keys - 1)));
    const TextureSpec& a = inputs[k];
    const TextureSpec& b = inputs[k + 1];
    const ShaderDecl& da = library.get(a.shader);
    const ShaderDecl& db = library.get(b.shader);
    const auto pa = resolve(da, a), pb = resolve(db, b);
    const MorphSpace sp(da);
    for (int f = (k == 0 ? fa : fa + 1); f <= fb; ++f) {
      const double t = fb > fa ? double(f - fa) / (fb - fa) : 0.0;
      Frame fr;
      fr.position = double(f) / std::max(1, frames - 1);
      if (f == fa) {
        fr.spec = spec_from_packed(da, pa, a.seed);
        fr.key = k;
      } else if (f == fb) {
        fr.spec = spec_from_packed(db, pb, b.seed);
        fr.key = k + 1;
      } else if (a.shader == b.shader) {
        fr.spec = spec_from_packed(da, sp.lerp(pa, pb, t), seed);
      } else {  // no shared parameter space: a plain cross-fade
        fr.spec = spec_from_packed(da, pa, seed);
        fr.blend_to = spec_from_packed(db, pb, seed);
        fr.blend = t;
      }
      out.push_back(std::move(fr));
    }
  }
  return out;
}

}  // namespace proctex::transform
