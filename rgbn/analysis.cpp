#include "rgbn/analysis.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

#include "core/error.h"
#include "rgbn/parallel.h"

namespace proctex::rgbn {

Curvature curvature(const Rgbn& image, bool wrap) {
  const int w = image.width, h = image.height;
  std::vector<float> p, q;
  slopes(image, p, q);
  Curvature c;
  c.K.assign(image.size(), 0.0f);
  c.H.assign(image.size(), 0.0f);
  auto idx = [&](int x, int y) {
    if (wrap) x = (x % w + w) % w, y = (y % h + h) % h;
    else x = std::clamp(x, 0, w - 1), y = std::clamp(y, 0, h - 1);
    return size_t(y) * w + x;
  };
  detail::parallel_rows(h, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const int xl = x - 1, xr = x + 1, yu = y - 1, yd = y + 1;
        const float dx = (wrap || (xl >= 0 && xr < w)) ? 2.0f : 1.0f;
        const float dy = (wrap || (yu >= 0 && yd < h)) ? 2.0f : 1.0f;
        // y up: the row above is +y.
        const float zxx = (p[idx(xr, y)] - p[idx(xl, y)]) / dx;
        const float zyy = (q[idx(x, yu)] - q[idx(x, yd)]) / dy;
        const float zxy = 0.5f * ((p[idx(x, yu)] - p[idx(x, yd)]) / dy + (q[idx(xr, y)] - q[idx(xl, y)]) / dx);
        const float zx = p[i], zy = q[i];
        const float g = 1.0f + zx * zx + zy * zy;
        c.K[i] = (zxx * zyy - zxy * zxy) / (g * g);
        // Mean curvature of the graph z(x, y); negated so that a bump towards the viewer is H > 0.
        c.H[i] = -((1 + zy * zy) * zxx - 2 * zx * zy * zxy + (1 + zx * zx) * zyy) / (2 * g * std::sqrt(g));
      }
  });
  return c;
}

EdgeWeight parse_edge_weight(const std::string& name) {
  if (name == "min") return EdgeWeight::Min;
  if (name == "max") return EdgeWeight::Max;
  if (name == "mix") return EdgeWeight::Mix;
  throw UsageError("unknown edge weight '" + name + "'", "use min, max or mix");
}

namespace {
struct Forest {
  std::vector<int> parent, size;
  std::vector<float> internal;
  explicit Forest(int n) : parent(n), size(n, 1), internal(n, 0.0f) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  int join(int a, int b, float w) {
    if (size[a] < size[b]) std::swap(a, b);
    parent[b] = a;
    size[a] += size[b];
    internal[a] = w;
    return a;
  }
};
struct Edge {
  float w;
  int a, b;
};
}  // namespace

Segmentation segment(const Rgbn& image, const SegmentOptions& o) {
  if (!(o.k > 0) || o.min_size < 0 || !(o.alpha >= 0 && o.alpha <= 1))
    throw UsageError("segmentation needs k > 0, min size >= 0 and alpha in [0, 1]", "e.g. --k 0.5 --min-size 50");
  const int w = image.width, h = image.height;
  auto weight = [&](size_t i, size_t j) {
    const float* a = &image.albedo[3 * i];
    const float* b = &image.albedo[3 * j];
    const float* m = &image.normal[3 * i];
    const float* n = &image.normal[3 * j];
    const float dc = std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
    const float dn = std::sqrt((m[0] - n[0]) * (m[0] - n[0]) + (m[1] - n[1]) * (m[1] - n[1]) + (m[2] - n[2]) * (m[2] - n[2]));
    switch (o.weight) {
      case EdgeWeight::Min: return std::min(dc, dn);
      case EdgeWeight::Max: return std::max(dc, dn);
      case EdgeWeight::Mix: break;
    }
    return (1 - o.alpha) * dc + o.alpha * dn;
  };
  // Four edges per pixel (right, down, down-right, down-left) at fixed slots, built in parallel;
  // slots without a neighbour get a negative weight and are dropped.
  std::vector<Edge> all(image.size() * 4);
  detail::parallel_rows(h, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        Edge* e = &all[4 * i];
        e[0] = x + 1 < w ? Edge{weight(i, i + 1), int(i), int(i + 1)} : Edge{-1, 0, 0};
        e[1] = y + 1 < h ? Edge{weight(i, i + w), int(i), int(i + w)} : Edge{-1, 0, 0};
        e[2] = x + 1 < w && y + 1 < h ? Edge{weight(i, i + w + 1), int(i), int(i + w + 1)} : Edge{-1, 0, 0};
        e[3] = x > 0 && y + 1 < h ? Edge{weight(i, i + w - 1), int(i), int(i + w - 1)} : Edge{-1, 0, 0};
      }
  });
  std::vector<Edge> edges;
  edges.reserve(all.size());
  for (const Edge& e : all)
    if (e.w >= 0) edges.push_back(e);
  std::vector<Edge>().swap(all);
  // Counting sort on the weight quantised to 2^16 levels (stable: ties keep pixel order). A
  // comparison sort of the 4 N edges took most of the time on large images.
  {
    float top = 0;
    for (const Edge& e : edges) top = std::max(top, e.w);
    const float scale = top > 0 ? 65535.0f / top : 0.0f;
    std::vector<uint32_t> start(65537, 0);
    for (const Edge& e : edges) ++start[size_t(e.w * scale) + 1];
    for (size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    std::vector<Edge> sorted(edges.size());
    for (const Edge& e : edges) sorted[start[size_t(e.w * scale)]++] = e;
    edges.swap(sorted);
  }
  Forest f(int(image.size()));
  std::vector<float> threshold(image.size(), o.k);
  for (const Edge& e : edges) {
    int a = f.find(e.a), b = f.find(e.b);
    if (a == b) continue;
    if (e.w <= threshold[a] && e.w <= threshold[b]) {
      a = f.join(a, b, e.w);
      threshold[a] = e.w + o.k / float(f.size[a]);
    }
  }
  for (const Edge& e : edges) {
    const int a = f.find(e.a), b = f.find(e.b);
    if (a != b && (f.size[a] < o.min_size || f.size[b] < o.min_size)) f.join(a, b, e.w);
  }
  Segmentation s;
  s.labels.assign(image.size(), -1);
  std::vector<int> id(image.size(), -1);
  for (size_t i = 0; i < image.size(); ++i) {
    const int r = f.find(int(i));
    if (id[r] < 0) id[r] = s.count++;
    s.labels[i] = id[r];
  }
  return s;
}

}  // namespace proctex::rgbn
