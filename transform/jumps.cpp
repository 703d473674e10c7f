#include "transform/jumps.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

#include "core/error.h"
#include "metrics/metric.h"
#include "search/colour_fit.h"
#include "search/objective.h"
#include "search/refine.h"
#include "shaders/parameter_space.h"
#include "transform/frames.h"

namespace proctex::transform {
namespace {

using Clock = std::chrono::steady_clock;

std::vector<int> sparse_indices(const catalog::ShaderCatalogue& c, int sparse) {
  std::vector<int> idx;
  if (sparse <= 0 && !c.pruned.empty()) return c.pruned;
  const int n = static_cast<int>(c.samples.size());
  const int k = sparse <= 0 ? n : std::min(sparse, n);
  for (int i = 0; i < k; ++i) idx.push_back(static_cast<int>(int64_t(i) * n / k));
  return idx;
}

struct Candidate {
  int a, b;
  double similarity;
};

// The most similar sparse pairs, each sample of either shader used at most once (distinct regions).
std::vector<Candidate> start_pairs(const catalog::ShaderCatalogue& a, const catalog::ShaderCatalogue& b, int sparse,
                                   int count) {
  const auto& metric = metrics::default_metric();
  std::vector<Candidate> all;
  for (int i : sparse_indices(a, sparse))
    for (int j : sparse_indices(b, sparse))
      all.push_back({i, j, metric.similarity(a.samples[i].features, b.samples[j].features)});
  std::sort(all.begin(), all.end(), [](const Candidate& x, const Candidate& y) { return x.similarity > y.similarity; });
  std::vector<Candidate> out;
  std::set<int> used_a, used_b;
  for (const auto& c : all) {
    if (static_cast<int>(out.size()) >= count) break;
    if (used_a.count(c.a) || used_b.count(c.b)) continue;
    used_a.insert(c.a);
    used_b.insert(c.b);
    out.push_back(c);
  }
  return out;
}

std::vector<double> to_double(const std::vector<float>& v) { return {v.begin(), v.end()}; }

void check_current(const catalog::ShaderCatalogue& c) {
  const auto& metric = metrics::default_metric();
  if (c.samples.empty()) throw Error("catalogue shader '" + c.shader + "' has no samples", "rebuild it");
  const auto& f = c.samples.front().features;
  if (f.metric != metric.id() || f.version != metric.version())
    throw Error("catalogue shader '" + c.shader + "' has " + f.metric + " v" + std::to_string(f.version) +
                    " features, this proctex computes " + metric.id() + " v" + std::to_string(metric.version()),
                "rebuild it: proctex catalog build --shaders " + c.shader);
}

}  // namespace

nlohmann::json PairReport::to_json() const {
  return {{"a", a}, {"b", b}, {"sparse_best", sparse_best}, {"start", start}, {"refined", refined},
          {"renders", renders}, {"seconds", seconds}};
}

nlohmann::json LinkReport::to_json() const {
  nlohmann::json j = {{"pairs", nlohmann::json::array()}, {"seconds", seconds}};
  for (const auto& p : pairs) j["pairs"].push_back(p.to_json());
  return j;
}

std::vector<catalog::JumpEdge> find_jumps(const catalog::ShaderCatalogue& a, const catalog::ShaderCatalogue& b,
                                          Renderer& renderer, const LinkOptions& o, PairReport* report) {
  const auto t0 = Clock::now();
  check_current(a);
  check_current(b);
  const auto& metric = metrics::default_metric();
  const ShaderDecl& da = renderer.library().get(a.shader);
  const ShaderDecl& db = renderer.library().get(b.shader);
  const ParameterSpace sa(da), sb(db);  // the catalogue's space: searchable parameters, defaults elsewhere
  const int full = a.samples.front().features.resolution;
  if (b.samples.front().features.resolution != full)
    throw Error("catalogue shaders '" + a.shader + "' and '" + b.shader + "' have different resolutions",
                "rebuild them with the same --resolution");
  const int coarse = std::clamp(o.resolution / 16 * 16, metrics::kMinResolution, full);
  const uint32_t seed_a = a.samples.front().seed, seed_b = b.samples.front().seed;

  search::RefineOptions ro;
  ro.max_evaluations = o.evaluations;
  ro.max_restarts = 1;
  ro.tolerance = o.tolerance;
  long renders = 0;
  auto render_one = [&](const ShaderDecl& d, const std::vector<float>& packed, uint32_t seed, int res) {
    ++renders;
    return render_features(renderer, d, {packed}, {seed}, res, 1).front();
  };

  std::vector<catalog::JumpEdge> out;
  PairReport local;
  local.a = a.shader;
  local.b = b.shader;
  const auto starts = start_pairs(a, b, o.sparse, o.jumps);
  if (!starts.empty()) local.sparse_best = starts.front().similarity;
  for (const auto& st : starts) {
    std::vector<double> x = to_double(a.samples[st.a].unit), y = to_double(b.samples[st.b].unit);
    metrics::Features fx = render_one(da, sa.to_packed(x), seed_a, coarse);
    double previous = -1;
    int rounds = 0;
    for (; rounds < o.rounds; ++rounds) {
      // y against the render of x, then x against the render of y (thesis: alternate until the
      // steps become negligible).
      search::Objective ob(sb, fx, metric, renderer, seed_b, coarse);
      y = search::refine(ob, y, ro).unit;
      renders += ob.evaluations();
      const metrics::Features fy = render_one(db, sb.to_packed(y), seed_b, coarse);
      search::Objective oa(sa, fy, metric, renderer, seed_a, coarse);
      const auto rx = search::refine(oa, x, ro);
      renders += oa.evaluations();
      x = rx.unit;
      fx = render_one(da, sa.to_packed(x), seed_a, coarse);
      if (rx.similarity - previous < o.tolerance) {
        ++rounds;
        break;
      }
      previous = rx.similarity;
    }
    catalog::JumpEdge e;
    e.shader_a = a.shader;
    e.shader_b = b.shader;
    e.seed_a = seed_a;
    e.seed_b = seed_b;
    e.packed_a = sa.to_packed(x);
    e.packed_b = sb.to_packed(y);
    e.features_a = render_one(da, e.packed_a, seed_a, full);
    e.features_b = render_one(db, e.packed_b, seed_b, full);
    e.similarity = metric.similarity(e.features_a, e.features_b);
    local.start.push_back(st.similarity);
    if (e.similarity < st.similarity) {  // the coarse optimum was a poor proxy: keep the start pair
      e.packed_a = a.samples[st.a].packed;
      e.packed_b = b.samples[st.b].packed;
      e.features_a = a.samples[st.a].features;
      e.features_b = b.samples[st.b].features;
      e.similarity = st.similarity;
    }
    local.refined.push_back(e.similarity);
    e.info = {{"start", {{"a", st.a}, {"b", st.b}, {"similarity", st.similarity}}},
              {"rounds", rounds},
              {"refined", e.similarity > st.similarity},
              {"resolution", coarse}};
    out.push_back(std::move(e));
  }
  std::sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.similarity > y.similarity; });
  local.renders = renders;
  local.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  if (report) *report = local;
  return out;
}

namespace {

// `packed` (of `to`) with every searchable parameter that `from` declares under the same name and
// type taken from `source` (clamped to to's range): shaders of one family share names for the
// same thing (fg, bg, softness), so a start that already agrees there is closer.
std::vector<float> with_shared_names(const ShaderDecl& to, std::vector<float> packed, const ShaderDecl& from,
                                     const std::vector<float>& source) {
  for (const auto& p : to.params) {
    const ParamDecl* q = from.find(p.name);
    if (!p.searchable || !q || q->type != p.type || q->width() != p.width()) continue;
    for (int c = 0; c < p.width(); ++c) packed[p.offset + c] = std::clamp(source[q->offset + c], p.min, p.max);
  }
  return packed;
}

}  // namespace

catalog::JumpEdge anchor_jump(const std::string& shader, const std::vector<float>& packed, uint32_t key_seed,
                              const metrics::Features& features, const catalog::ShaderCatalogue& other,
                              const std::vector<float>& base, uint32_t seed, Renderer& renderer,
                              const AnchorOptions& o) {
  check_current(other);
  const auto& metric = metrics::default_metric();
  const ShaderDecl& dk = renderer.library().get(shader);
  const ShaderDecl& dt = renderer.library().get(other.shader);
  const ParameterSpace space(dt, base);
  const int full = features.resolution;
  const int coarse = std::clamp(o.resolution / 16 * 16, metrics::kMinResolution, full);

  // Start points: the catalogue samples of `other` most similar to the texture (stored features),
  // each also with the parameters the two shaders share by name taken from the texture; then their
  // colours fitted to the texture's render (search::fit_colours, the matcher's closed-form fit).
  std::vector<std::pair<double, int>> ranked;
  for (size_t i = 0; i < other.samples.size(); ++i)
    ranked.emplace_back(metric.similarity(features, other.samples[i].features), static_cast<int>(i));
  const size_t top = std::min<size_t>(std::max(o.starts, 1), ranked.size());
  std::partial_sort(ranked.begin(), ranked.begin() + top, ranked.end(), std::greater<>());
  std::vector<std::vector<float>> starts;
  for (size_t k = 0; k < top; ++k) {
    const auto p = space.to_packed(space.to_unit(other.samples[ranked[k].second].packed));
    starts.push_back(p);
    starts.push_back(space.to_packed(space.to_unit(with_shared_names(dt, p, dk, packed))));
  }
  RenderSettings rs;
  rs.width = rs.height = coarse;
  const Image key_image = renderer.render_batch(dk, {packed}, {key_seed}, rs).front();
  const metrics::Features target = metric.features(key_image, coarse);
  const auto fits = search::fit_colours(dt, starts, std::vector<uint32_t>(starts.size(), seed), {},
                                        search::make_colour_target(key_image), renderer, false);
  for (size_t k = 0; k < fits.size(); ++k)
    if (fits[k].fitted) starts.push_back(space.to_packed(space.to_unit(fits[k].packed)));

  // Refine the best starts at the coarse resolution (one launch scores them all).
  search::Objective ob(space, target, metric, renderer, seed, coarse);
  std::vector<std::vector<double>> units;
  for (const auto& p : starts) units.push_back(space.to_unit(p));
  const auto start_scores = ob.evaluate(units);
  std::vector<size_t> order(units.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return start_scores[a] > start_scores[b]; });
  const size_t refined = std::min<size_t>(2, order.size());
  search::RefineOptions ro;
  ro.max_evaluations = std::max<long>(1, o.evaluations / static_cast<long>(refined));
  ro.max_restarts = 1;
  std::vector<std::vector<float>> candidates = {space.to_packed(units[order[0]])};
  double best = -1;
  std::vector<double> best_unit;
  for (size_t k = 0; k < refined; ++k) {
    const auto r = search::refine(ob, units[order[k]], ro);
    if (r.similarity > best) {
      best = r.similarity;
      best_unit = r.unit;
    }
  }
  candidates.push_back(space.to_packed(best_unit));
  // The coarse optimum is a proxy: keep whichever of it and the best start looks more alike at the
  // catalogue resolution.
  const auto scored = render_features(renderer, dt, candidates, std::vector<uint32_t>(candidates.size(), seed), full, 1);
  std::vector<double> sims;
  size_t pick = 0;
  for (size_t i = 0; i < scored.size(); ++i) {
    sims.push_back(metric.similarity(features, scored[i]));
    if (sims[i] > sims[pick]) pick = i;
  }
  catalog::JumpEdge e;
  e.shader_a = shader;
  e.shader_b = other.shader;
  e.packed_a = packed;
  e.packed_b = candidates[pick];
  e.seed_a = key_seed;
  e.seed_b = seed;
  e.features_a = features;
  e.features_b = scored[pick];
  e.similarity = sims[pick];
  e.info = {{"anchored", true},
            {"start", {{"sample", ranked[0].second}, {"similarity", ranked[0].first}, {"best_start", sims[0]}}},
            {"refined", pick > 0},
            {"evaluations", ob.evaluations() + static_cast<long>(2 + search::colour_fit_renders(dt, {}, fits.size()))},
            {"resolution", coarse}};
  return e;
}

std::vector<std::pair<std::string, std::string>> choose_pairs(catalog::Store& store, const std::vector<std::string>& shaders,
                                                             const LinkOptions& o) {
  std::set<std::string> names(shaders.begin(), shaders.end());
  if (names.size() < 2) throw UsageError("catalog link needs at least two shaders", "e.g. --shaders rectangle,superellipse,circle");
  std::map<std::string, catalog::ShaderCatalogue> cats;
  for (const auto& s : names) cats.emplace(s, store.load(s, false));
  const auto& metric = metrics::default_metric();
  std::set<std::pair<std::string, std::string>> pairs;
  for (const auto& s : names) {
    std::vector<std::pair<double, std::string>> partners;
    for (const auto& t : names) {
      if (t == s) continue;
      double best = 0;
      for (int i : sparse_indices(cats.at(s), o.sparse))
        for (int j : sparse_indices(cats.at(t), o.sparse))
          best = std::max(best, metric.similarity(cats.at(s).samples[i].features, cats.at(t).samples[j].features));
      partners.emplace_back(best, t);
    }
    std::sort(partners.begin(), partners.end(), std::greater<>());
    const int keep = o.neighbours <= 0 ? static_cast<int>(partners.size()) : std::min<int>(o.neighbours, partners.size());
    for (int k = 0; k < keep; ++k) pairs.insert({std::min(s, partners[k].second), std::max(s, partners[k].second)});
  }
  return {pairs.begin(), pairs.end()};
}

LinkReport link(catalog::Store& store, const std::vector<std::pair<std::string, std::string>>& pairs,
                const LinkOptions& o, Renderer& renderer, const std::function<void(const LinkProgress&)>& progress) {
  const auto t0 = Clock::now();
  LinkReport report;
  std::map<std::string, catalog::ShaderCatalogue> cats;
  auto cat = [&](const std::string& s) -> const catalog::ShaderCatalogue& {
    auto it = cats.find(s);
    if (it == cats.end()) it = cats.emplace(s, store.load(s, false)).first;
    return it->second;
  };
  for (size_t i = 0; i < pairs.size(); ++i) {
    const auto& [a, b] = pairs[i];
    if (progress) progress({a, b, static_cast<int>(i), static_cast<int>(pairs.size())});
    PairReport r;
    const auto jumps = find_jumps(cat(a), cat(b), renderer, o, &r);
    store.write_jumps(a, b, jumps);
    report.pairs.push_back(std::move(r));
  }
  report.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return report;
}

}  // namespace proctex::transform
