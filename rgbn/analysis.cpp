#include "rgbn/analysis.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <numeric>
#include <thread>

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
// Union-find forest in 4 bytes per pixel: node[x] >= 0 is x's parent; a root holds the bits of
// minus its FH threshold Int(C) + k/|C| (> 0, so the int is negative). The union loop visits
// pixels in weight order, i.e. at random, and is bound by memory latency: one 4-byte word per
// pixel (16 MB at 2048^2) keeps more of the forest in cache than separate arrays. Sizes are read
// only when components join.
struct Forest {
  std::vector<int32_t> node;
  std::vector<int> size;
  Forest(int n, float k) : node(size_t(n), std::bit_cast<int32_t>(-k)), size(size_t(n), 1) {}
  int find(int x) {
    for (;;) {
      const int p = node[size_t(x)];
      if (p < 0) return x;
      const int g = node[size_t(p)];
      if (g < 0) return p;
      node[size_t(x)] = g;  // path halving
      x = g;
    }
  }
  float threshold(int root) const { return -std::bit_cast<float>(node[size_t(root)]); }
  void set_threshold(int root, float t) { node[size_t(root)] = std::bit_cast<int32_t>(-t); }
  int join(int a, int b) {  // roots; returns the new root (keeps its old threshold)
    if (size[size_t(a)] < size[size_t(b)]) std::swap(a, b);
    node[size_t(b)] = a;
    size[size_t(a)] += size[size_t(b)];
    return a;
  }
};
// An edge: its weight and 4 * pixel + slot (slot 0..3 = right, down, down-right, down-left).
struct Edge {
  float w;
  uint32_t id;
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
  // Four edge slots per pixel (right, down, down-right, down-left), weights computed in parallel;
  // slots without a neighbour get a negative weight and are skipped.
  const size_t N = image.size();
  const int64_t offset[4] = {1, w, int64_t(w) + 1, int64_t(w) - 1};
  std::vector<float> weights(N * 4);
  float top = 0;  // the largest weight
  std::mutex top_lock;
  detail::parallel_rows(h, [&](int y0, int y1) {
    float band_top = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        float* e = &weights[4 * i];
        e[0] = x + 1 < w ? weight(i, i + 1) : -1.0f;
        e[1] = y + 1 < h ? weight(i, i + w) : -1.0f;
        e[2] = x + 1 < w && y + 1 < h ? weight(i, i + w + 1) : -1.0f;
        e[3] = x > 0 && y + 1 < h ? weight(i, i + w - 1) : -1.0f;
        band_top = std::max(band_top, std::max(std::max(e[0], e[1]), std::max(e[2], e[3])));
      }
    const std::lock_guard<std::mutex> lock(top_lock);
    top = std::max(top, band_top);
  });
  // Counting sort on the weight quantised to 2^16 levels (stable: ties keep pixel order). A
  // comparison sort of the 4 N edges took most of the time on large images. The edge slots are
  // cut into one contiguous chunk per core; each counts its chunk, and chunk t's edges of a bucket
  // go after those of chunks < t, so the parallel scatter is the serial stable one.
  std::vector<Edge> edges;
  {
    const int T = int(std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
    const size_t S = weights.size(), chunk = (S + T - 1) / T;
    constexpr size_t B = 65536;
    std::vector<std::vector<uint32_t>> count(T);
    auto in_threads = [&](auto&& body) {
      std::vector<std::thread> pool;
      for (int t = 1; t < T; ++t) pool.emplace_back([&body, t] { body(t); });
      body(0);
      for (auto& th : pool) th.join();
    };
    const float scale = top > 0 ? float(B - 1) / top : 0.0f;
    in_threads([&](int t) {
      count[t].assign(B, 0);
      for (size_t e = t * chunk; e < std::min(S, (t + 1) * chunk); ++e)
        if (weights[e] >= 0) ++count[t][size_t(weights[e] * scale)];
    });
    // count[t][b] becomes the first output slot of chunk t's edges in bucket b.
    uint32_t next = 0;
    for (size_t b = 0; b < B; ++b)
      for (int t = 0; t < T; ++t) {
        const uint32_t c = count[t][b];
        count[t][b] = next;
        next += c;
      }
    edges.resize(next);
    in_threads([&](int t) {
      uint32_t* slot = count[t].data();
      for (size_t e = t * chunk; e < std::min(S, (t + 1) * chunk); ++e)
        if (weights[e] >= 0) edges[slot[size_t(weights[e] * scale)]++] = {weights[e], uint32_t(e)};
    });
  }
  std::vector<float>().swap(weights);
  Forest f(int(N), o.k);
  // The loops below visit pixels at random: prefetching the nodes of the edge kPrefetch ahead
  // overlaps the cache misses.
  constexpr size_t kPrefetch = 16;
  auto prefetch = [&](size_t k) {
    if (k + kPrefetch < edges.size()) {
      const uint32_t id = edges[k + kPrefetch].id;
      __builtin_prefetch(&f.node[id >> 2]);
      __builtin_prefetch(&f.node[size_t(int64_t(id >> 2) + offset[id & 3])]);
    }
    if (k + kPrefetch / 2 < edges.size()) {  // their parents, now that the nodes are (nearly) in cache
      const uint32_t id = edges[k + kPrefetch / 2].id;
      const int pa = f.node[id >> 2], pb = f.node[size_t(int64_t(id >> 2) + offset[id & 3])];
      if (pa >= 0) __builtin_prefetch(&f.node[size_t(pa)]);
      if (pb >= 0) __builtin_prefetch(&f.node[size_t(pb)]);
    }
  };
  for (size_t k = 0; k < edges.size(); ++k) {
    prefetch(k);
    const Edge& e = edges[k];
    const int pa = int(e.id >> 2);
    int a = f.find(pa), b = f.find(int(pa + offset[e.id & 3]));
    if (a == b) continue;
    if (e.w <= f.threshold(a) && e.w <= f.threshold(b)) {
      a = f.join(a, b);
      f.set_threshold(a, e.w + o.k / float(f.size[size_t(a)]));
    }
  }
  // Small components merge into a neighbour, in weight order. Components only grow, so an edge
  // between two pixels whose components are already >= min_size can never merge: only edges
  // touching a small component are visited.
  if (o.min_size > 1) {
    // One bit per pixel (512 KB at 2048^2: the random lookups stay in the L2 cache).
    std::vector<uint64_t> small((N + 63) / 64, 0);
    for (size_t i = 0; i < N; ++i)
      if (f.size[size_t(f.find(int(i)))] < o.min_size) small[i >> 6] |= uint64_t(1) << (i & 63);
    auto is_small = [&](size_t i) { return (small[i >> 6] >> (i & 63)) & 1; };
    for (size_t k = 0; k < edges.size(); ++k) {
      const Edge& e = edges[k];
      const int pa = int(e.id >> 2), pb = int(pa + offset[e.id & 3]);
      if (!is_small(size_t(pa)) && !is_small(size_t(pb))) continue;
      prefetch(k);
      const int a = f.find(pa), b = f.find(pb);
      if (a != b && (f.size[size_t(a)] < o.min_size || f.size[size_t(b)] < o.min_size)) f.join(a, b);
    }
  }
  Segmentation s;
  s.labels.assign(N, -1);
  std::vector<int> id(N, -1);
  for (size_t i = 0; i < N; ++i) {
    const int r = f.find(int(i));
    if (id[size_t(r)] < 0) id[size_t(r)] = s.count++;
    s.labels[i] = id[size_t(r)];
  }
  return s;
}

}  // namespace proctex::rgbn
