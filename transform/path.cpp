#include "transform/path.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

#include "core/error.h"

namespace proctex::transform {

void Graph::add_edge(int a, int b, double weight) {
  const double w = std::clamp(weight, 0.0, 1.0);
  adjacency_[a].emplace_back(b, w);
  adjacency_[b].emplace_back(a, w);
}

std::optional<Path> shortest_path(const Graph& graph, int source, int target, double power) {
  if (power < 1) throw UsageError("--power must be at least 1", "the thesis uses n = 1, 2, 3");
  const int n = graph.size();
  // Distances are kept as sums of e^n (monotone in the eq 5.1 cost, and exact under addition).
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<int> previous(n, -1);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[source] = 0;
  queue.emplace(0.0, source);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    if (v == target) break;
    for (const auto& [u, w] : graph.neighbours(v)) {
      const double nd = d + std::pow(w, power);
      if (nd < dist[u]) {
        dist[u] = nd;
        previous[u] = v;
        queue.emplace(nd, u);
      }
    }
  }
  if (!std::isfinite(dist[target])) return std::nullopt;
  Path p;
  p.cost = std::pow(dist[target], 1.0 / power);
  for (int v = target; v != -1; v = previous[v]) p.vertices.push_back(v);
  std::reverse(p.vertices.begin(), p.vertices.end());
  return p;
}

}  // namespace proctex::transform
