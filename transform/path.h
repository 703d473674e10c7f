#pragma once
// Shortest paths with the thesis's power-n cost (section 5.2, eq 5.1): edges weigh the
// dissimilarity 1 - S of their ends, and a path costs (e_1^n + ... + e_m^n)^(1/n), computed
// incrementally as d[j] = (d[i]^n + e(i, j)^n)^(1/n). Minimising the sum of e^n is equivalent.
// n = 1 is the plain sum; larger n prefers more, smaller steps (thesis fig 5-2).
#include <optional>
#include <utility>
#include <vector>

namespace proctex::transform {

class Graph {
 public:
  explicit Graph(int vertices = 0) : adjacency_(vertices) {}
  int add_vertex() {
    adjacency_.emplace_back();
    return static_cast<int>(adjacency_.size()) - 1;
  }
  // Undirected edge; `weight` is a dissimilarity (1 - S), clamped to [0, 1].
  void add_edge(int a, int b, double weight);
  int size() const { return static_cast<int>(adjacency_.size()); }
  const std::vector<std::pair<int, double>>& neighbours(int v) const { return adjacency_[v]; }

 private:
  std::vector<std::vector<std::pair<int, double>>> adjacency_;
};

struct Path {
  std::vector<int> vertices;  // from source to target
  double cost = 0;            // (sum e^n)^(1/n)
};

// Dijkstra with the power-n cost; nullopt when `target` is unreachable. power >= 1.
std::optional<Path> shortest_path(const Graph& graph, int source, int target, double power);

}  // namespace proctex::transform
