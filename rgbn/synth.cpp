#include "rgbn/synth.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "core/error.h"
#include "rgbn/edit.h"
#include "rgbn/parallel.h"

namespace proctex::rgbn {

Order parse_order(const std::string& name) {
  if (name == "hilbert") return Order::Hilbert;
  if (name == "dfs") return Order::ShuffledDfs;
  throw UsageError("unknown traversal order '" + name + "'", "use hilbert or dfs");
}

JumpMap build_jump_map(const Rgbn& ex, const JumpMapOptions& o) {
  if (o.neighbourhood < 1 || o.neighbourhood % 2 == 0 || o.neighbourhood > 15)
    throw UsageError("the neighbourhood must be odd and at most 15", "e.g. 5");
  if (o.jumps < 1 || o.jumps > 32) throw UsageError("jumps per pixel must be in [1, 32]", "e.g. 4");
  const int w = ex.width, h = ex.height, M = o.neighbourhood, r = M / 2;
  const size_t N = ex.size();
  const int D = 6 * M * M;
  Eigen::MatrixXf F(N, D);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      int k = 0;
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
          const int xx = std::clamp(x + i, 0, w - 1), yy = std::clamp(y + j, 0, h - 1);
          for (int c = 0; c < 3; ++c) F(size_t(y) * w + x, k++) = ex.a(xx, yy)[c];
          for (int c = 0; c < 3; ++c) F(size_t(y) * w + x, k++) = ex.n(xx, yy)[c];
        }
    }
  // PCA keeping `variance` of the total.
  const Eigen::RowVectorXf mean = F.colwise().mean();
  F.rowwise() -= mean;
  const Eigen::MatrixXf C = (F.transpose() * F) / float(std::max<size_t>(1, N - 1));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXf> eig(C);
  const Eigen::VectorXf ev = eig.eigenvalues().reverse();
  const double total = std::max(1e-20, double(ev.sum()));
  int keep = 0;
  double acc = 0;
  while (keep < D && acc < o.variance * total) acc += ev(keep++);
  keep = std::max(1, keep);
  const Eigen::MatrixXf basis = eig.eigenvectors().rowwise().reverse().leftCols(keep);
  const Eigen::MatrixXf P = F * basis;  // N x keep
  // Candidates: a seeded subset (or all).
  std::vector<int> cand(N);
  std::iota(cand.begin(), cand.end(), 0);
  std::mt19937_64 rng(o.seed);
  if (int(N) > o.candidates) {
    std::shuffle(cand.begin(), cand.end(), rng);
    cand.resize(o.candidates);
    std::sort(cand.begin(), cand.end());
  }
  JumpMap map;
  map.width = w, map.height = h, map.dimensions = keep;
  map.jumps.resize(N);
  const Eigen::MatrixXf Pc = P(cand, Eigen::all);
  const Eigen::VectorXf cn = Pc.rowwise().squaredNorm();
  detail::parallel_rows(h, [&](int y0, int y1) {
    std::vector<std::pair<float, int>> best;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        const size_t p = size_t(y) * w + x;
        const Eigen::VectorXf d = cn - 2.0f * (Pc * P.row(p).transpose());
        best.clear();
        for (size_t k = 0; k < cand.size(); ++k) {
          const int c = cand[k];
          const int cx = c % w, cy = c / w;
          if (std::abs(cx - x) <= M && std::abs(cy - y) <= M) continue;  // not itself or its overlap
          best.push_back({d(k), c});
        }
        const size_t K = std::min<size_t>(o.jumps, best.size());
        std::partial_sort(best.begin(), best.begin() + K, best.end());
        for (size_t k = 0; k < K; ++k) map.jumps[p].push_back(best[k].second);
      }
  }, 16);
  return map;
}

namespace {

// Hilbert index -> (x, y) on a 2^k grid (the classic iterative conversion).
void d2xy(int n, int d, int& x, int& y) {
  x = y = 0;
  for (int s = 1, t = d; s < n; s *= 2, t /= 4) {
    const int rx = 1 & (t / 2), ry = 1 & (t ^ rx);
    if (ry == 0) {
      if (rx == 1) x = s - 1 - x, y = s - 1 - y;
      std::swap(x, y);
    }
    x += s * rx, y += s * ry;
  }
}

}  // namespace

std::vector<int> visit_order(int w, int h, const std::vector<char>& inside, Order order, uint64_t seed) {
  std::vector<int> out;
  if (order == Order::Hilbert) {
    int n = 1;
    while (n < std::max(w, h)) n *= 2;
    for (long d = 0; d < long(n) * n; ++d) {
      int x, y;
      d2xy(n, int(d), x, y);
      if (x < w && y < h && inside[size_t(y) * w + x]) out.push_back(y * w + x);
    }
    return out;
  }
  std::mt19937_64 rng(seed ^ 0x9e3779b97f4a7c15ull);
  std::vector<char> seen(size_t(w) * h, 0);
  std::vector<int> stack;
  const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
  for (int start = 0; start < w * h; ++start) {
    if (!inside[start] || seen[start]) continue;
    stack.push_back(start);
    seen[start] = 1;
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      out.push_back(p);
      int dirs[4] = {0, 1, 2, 3};
      std::shuffle(dirs, dirs + 4, rng);
      for (int k : dirs) {
        const int x = p % w + dx[k], y = p / w + dy[k];
        if (x < 0 || y < 0 || x >= w || y >= h) continue;
        const int q = y * w + x;
        if (inside[q] && !seen[q]) seen[q] = 1, stack.push_back(q);
      }
    }
  }
  return out;
}

namespace {

JumpSynthResult run(const Rgbn& ex, const JumpMap& map, Rgbn out, const std::vector<char>& inside,
                    const JumpSynthOptions& o) {
  if (map.width != ex.width || map.height != ex.height) throw Error("the jump map belongs to another example", "rebuild it");
  if (!(o.jump_probability >= 0 && o.jump_probability <= 1)) throw UsageError("--jump must be in [0, 1]", "e.g. 0.05");
  const int w = out.width, h = out.height, ew = ex.width, eh = ex.height;
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0, 1);
  JumpSynthResult res;
  res.source.assign(out.size(), -1);
  const std::vector<int> order = visit_order(w, h, inside, o.order, o.seed);
  size_t runs = 0, continued = 0;
  const int dx[4] = {-1, 0, 1, 0}, dy[4] = {0, -1, 0, 1};
  auto random_source = [&] { return int(rng() % uint64_t(ew * eh)); };
  // Known context: pixels already synthesised, and (fill) every pixel outside the region.
  auto known = [&](size_t q) { return !inside[q] || res.source[q] >= 0; };
  // Mismatch between the example around c and the known output around p (5x5, without p).
  auto cost = [&](int p, int c) {
    const int x = p % w, y = p / w, cx = c % ew, cy = c / ew;
    float sum = 0;
    int n = 0;
    for (int j = -2; j <= 2; ++j)
      for (int i = -2; i <= 2; ++i) {
        const int qx = x + i, qy = y + j, ex_x = cx + i, ex_y = cy + j;
        if ((i == 0 && j == 0) || qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
        const size_t q = size_t(qy) * w + qx;
        if (!known(q)) continue;
        if (ex_x < 0 || ex_y < 0 || ex_x >= ew || ex_y >= eh) {
          sum += 1.0f, ++n;  // the example has nothing there: a mild penalty
          continue;
        }
        const float* oa = &out.albedo[3 * q];
        const float* on = &out.normal[3 * q];
        const float* ea = ex.a(ex_x, ex_y);
        const float* en = ex.n(ex_x, ex_y);
        for (int k = 0; k < 3; ++k) sum += (oa[k] - ea[k]) * (oa[k] - ea[k]) + (on[k] - en[k]) * (on[k] - en[k]);
        ++n;
      }
    return n ? sum / float(n) : 0.0f;
  };
  auto best_of = [&](int p, const std::vector<int>& cs) {
    int best = cs[0];
    float bc = INFINITY;
    for (int c : cs) {
      const float v = cost(p, c);
      if (v < bc) bc = v, best = c;
    }
    return best;
  };
  std::vector<int> pool;
  for (int p : order) {
    const int x = p % w, y = p / w;
    // Candidates: continue each synthesised neighbour's source by the same offset.
    int cands[4], nc = 0, neighbour_src[4], nn = 0;
    for (int k = 0; k < 4; ++k) {
      const int qx = x + dx[k], qy = y + dy[k];
      if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
      const int s = res.source[size_t(qy) * w + qx];
      if (s < 0) continue;
      neighbour_src[nn++] = s;
      const int sx = s % ew - dx[k], sy = s / ew - dy[k];
      if (sx >= 0 && sy >= 0 && sx < ew && sy < eh) cands[nc++] = sy * ew + sx;
    }
    int src;
    const bool jump = nc == 0 || unit(rng) < o.jump_probability;
    if (!jump) {
      // Continue the run whose example neighbourhood fits the output best (coherence).
      pool.assign(cands, cands + nc);
      src = best_of(p, pool);
      ++continued;
    } else if (nn > 0) {
      // Jump: the targets of every neighbour's continuation (or source, at the example's edge),
      // the best-fitting one.
      pool.clear();
      for (int k = 0; k < (nc ? nc : nn); ++k)
        for (int t : map.jumps[nc ? cands[k] : neighbour_src[k]]) pool.push_back(t);
      if (pool.empty()) pool.push_back(random_source());
      src = best_of(p, pool);
      ++runs;
    } else {
      // A new start: the best of 64 random example pixels against the known context (fill
      // borders), or any when nothing is known.
      pool.clear();
      for (int k = 0; k < 64; ++k) pool.push_back(random_source());
      src = best_of(p, pool);
      ++runs;
    }
    res.source[p] = src;
    std::copy(ex.a(src % ew, src / ew), ex.a(src % ew, src / ew) + 3, out.a(x, y));
    std::copy(ex.n(src % ew, src / ew), ex.n(src % ew, src / ew) + 3, out.n(x, y));
  }
  res.visited = order.size();
  res.mean_run = runs ? double(continued + runs) / double(runs) : double(continued);
  res.image = std::move(out);
  return res;
}

}  // namespace

Rgbn base_normals(const Rgbn& im, float sigma) {
  FilterOptions f;
  f.kind = FilterKind::Smooth;
  f.sigma = sigma;
  return filter(im, f);
}

Vec3 compose_detail(const Rgbn& ex, const Rgbn& eb, int s, const Vec3& B) {
  const Vec3 x_axis = {1, 0, 0};
  const float* n = &ex.normal[3 * size_t(s)];
  const Vec3 b = {eb.normal[3 * size_t(s)], eb.normal[3 * size_t(s) + 1], eb.normal[3 * size_t(s) + 2]};
  Vec3 u, v;
  local_frame(b, x_axis, u, v);
  const float t[3] = {n[0] * u[0] + n[1] * u[1] + n[2] * u[2], n[0] * v[0] + n[1] * v[1] + n[2] * v[2],
                      n[0] * b[0] + n[1] * b[1] + n[2] * b[2]};
  local_frame(B, x_axis, u, v);
  Vec3 o;
  for (int c = 0; c < 3; ++c) o[c] = t[0] * u[c] + t[1] * v[c] + t[2] * B[c];
  const float l = std::sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
  for (int c = 0; c < 3; ++c) o[c] /= l;
  return o;
}

JumpSynthResult jump_synthesize(const Rgbn& ex, const JumpMap& map, int w, int h, const JumpSynthOptions& o) {
  check_dimensions(w, h);
  JumpSynthResult r = run(ex, map, Rgbn(w, h), std::vector<char>(size_t(w) * h, 1), o);
  if (o.xi >= 0) detail::saturate_synthesised(r.image, Rgbn(w, h), r.source, o.xi);
  return r;
}

JumpSynthResult jump_fill(const Rgbn& ex, const JumpMap& map, const Rgbn& target, const Mask& mask,
                          const JumpSynthOptions& o) {
  if (mask.size() != target.size()) throw Error("the fill mask is not the size of the target", "give a mask of the same size");
  std::vector<char> inside(mask.size());
  for (size_t i = 0; i < mask.size(); ++i) inside[i] = mask[i] > 0;
  JumpSynthResult r = run(ex, map, target, inside, o);
  if (o.compose) {
    // Detail of the example relative to its base, composed on the target's base normals.
    const Rgbn eb = base_normals(ex, o.base_sigma), tb = base_normals(target, o.base_sigma);
    for (size_t p = 0; p < target.size(); ++p) {
      const int s = r.source[p];
      if (s < 0) continue;
      const Vec3 n = compose_detail(ex, eb, s, {tb.normal[3 * p], tb.normal[3 * p + 1], tb.normal[3 * p + 2]});
      std::copy(n.begin(), n.end(), &r.image.normal[3 * p]);
    }
  }
  if (o.xi >= 0) detail::saturate_synthesised(r.image, target, r.source, o.xi);
  return r;
}

namespace detail {
void saturate_synthesised(Rgbn& out, const Rgbn& before, const std::vector<int>& source, double xi) {
  if (!(xi >= 0 && xi < 90)) throw UsageError("--xi must be in [0, 90) degrees", "e.g. --xi 10");
  for (size_t p = 0; p < out.size(); ++p) {
    if (source[p] < 0) continue;
    const Vec3 a = {before.normal[3 * p], before.normal[3 * p + 1], before.normal[3 * p + 2]};
    const Vec3 b = {out.normal[3 * p], out.normal[3 * p + 1], out.normal[3 * p + 2]};
    const Vec3 k = saturate_on_arc(a, b, xi);
    std::copy(k.begin(), k.end(), &out.normal[3 * p]);
  }
}
}  // namespace detail

}  // namespace proctex::rgbn
