#include "transform/jumps.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

#include "core/error.h"
#include "metrics/metric.h"
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
