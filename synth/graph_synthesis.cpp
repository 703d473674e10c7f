#include "synth/graph_synthesis.h"
#include "synth/cache_io.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <unistd.h>
#include <mutex>
#include <thread>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "core/error.h"
#include "core/parallel.h"
#include "core/hash.h"
#include "kernels/buffers.h"
#include "kernels/runtime.h"
#include "synth/analysis.h"
#include "synth/plane.h"
#include "synth/exemplar.h"

namespace proctex::synth {
namespace {

constexpr int kDims = kAppearanceDims;  // 8
// Han-style matching neighbourhood of the graph synthesis: the centre and its four diagonal
// neighbours (its own choice, independent of the single-exemplar synthesis' 3x3 taps).
constexpr int kTaps = 5;
constexpr int kGraphNeighbourDims = kAppearanceDims * kTaps;
constexpr int kColourTaps = 25;
constexpr int kAppIn = kColourTaps * 3;  // 75
constexpr int kLinkBias = 4;  // a continuing link may be 4/3 as far as the best (patch_match)

using detail::level_count;
using detail::reflect;
using detail::Sampler;
using detail::wrap;

// The Gaussian stack of an sRGB-encoded colour image (planar, 3 channels) as in analysis.cpp:
// level l = level l + 1 filtered with [1 4 6 4 1] / 16 at spacing 2^(L-l-1), separably.
std::vector<std::vector<float>> colour_stack(const std::vector<float>& planar, int L, const Sampler& s) {
  const int w = s.w, h = s.h;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<std::vector<float>> stack(L + 1);
  stack[L] = planar;
  const float k[5] = {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
  std::vector<float> tmp(planar.size());
  for (int l = L - 1; l >= 0; --l) {
    const int sp = 1 << (L - l - 1);
    const auto& src = stack[l + 1];
    auto& dst = stack[l];
    dst.assign(src.size(), 0.0f);
    for (int c = 0; c < 3; ++c) {
      const float* a = src.data() + c * n;
      float* t = tmp.data() + c * n;
      float* d = dst.data() + c * n;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          float acc = 0;
          for (int i = 0; i < 5; ++i) acc += k[i] * a[static_cast<size_t>(y) * w + s.ix(x + (i - 2) * sp)];
          t[static_cast<size_t>(y) * w + x] = acc;
        }
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
          float acc = 0;
          for (int i = 0; i < 5; ++i) acc += k[i] * t[static_cast<size_t>(s.iy(y + (i - 2) * sp)) * w + x];
          d[static_cast<size_t>(y) * w + x] = acc;
        }
    }
  }
  return stack;
}

Eigen::MatrixXd principal_axes(const Eigen::MatrixXd& cov, int dims, double& top_variance) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(cov);
  const int D = static_cast<int>(cov.rows());
  Eigen::MatrixXd axes = Eigen::MatrixXd::Zero(D, dims);
  for (int i = 0; i < std::min(dims, D); ++i) {
    Eigen::VectorXd v = es.eigenvectors().col(D - 1 - i);
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v(arg) < 0) v = -v;
    axes.col(i) = v;
  }
  top_variance = std::max(0.0, es.eigenvalues()(D - 1));
  return axes;
}

struct SplitMix {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  int below(int n) { return static_cast<int>(next() % static_cast<uint64_t>(n)); }
};

// PatchMatch: for every texel of a source stack level, the texel of a destination level (same
// size) minimising dist(source texel, destination texel); `step` = destination texels per source
// texel (2^r along an edge of scale r), `sep` > 0 = the match must be that far away (same level).
// `bias` > 0: a propagated match (continuing its neighbour's) counts (1 - 1/bias) of its distance, so
// the field of links stays coherent where a continuation is nearly as good (links made this way grow
// patches in the synthesis instead of scattering them).
template <typename Dist>
std::vector<int32_t> patch_match(int w, int h, bool dst_toroidal, int step, int sep, uint64_t seed, Dist dist,
                                 int bias = 0) {
  const size_t n = static_cast<size_t>(w) * h;
  auto far_enough = [&](int x0, int y0, int x1, int y1) {
    if (sep <= 0) return true;
    int dx = std::abs(x0 - x1), dy = std::abs(y0 - y1);
    if (dst_toroidal) dx = std::min(dx, w - dx), dy = std::min(dy, h - dy);
    return std::max(dx, dy) >= sep;
  };
  SplitMix rng{seed};
  std::vector<int32_t> nn(n);
  std::vector<int64_t> best(n);
  for (size_t i = 0; i < n; ++i) {
    const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
    int cx, cy;
    do {
      cx = rng.below(w), cy = rng.below(h);
    } while (!far_enough(x, y, cx, cy));
    nn[i] = cy * w + cx;
    best[i] = dist(i, static_cast<size_t>(nn[i]));
  }
  auto consider = [&](size_t i, int x, int y, int cx, int cy, bool propagated = false) {
    cx = dst_toroidal ? wrap(cx, w) : std::clamp(cx, 0, w - 1);
    cy = dst_toroidal ? wrap(cy, h) : std::clamp(cy, 0, h - 1);
    if (!far_enough(x, y, cx, cy)) return;
    const size_t c = static_cast<size_t>(cy) * w + cx;
    int64_t d = dist(i, c);
    if (propagated && bias > 0) d -= d / bias;
    if (d < best[i] || (d == best[i] && static_cast<int32_t>(c) < nn[i])) best[i] = d, nn[i] = static_cast<int32_t>(c);
  };
  for (int it = 0; it < 3; ++it) {
    const bool fwd = it % 2 == 0;
    const int dir = fwd ? 1 : -1;
    for (size_t k = 0; k < n; ++k) {
      const size_t i = fwd ? k : n - 1 - k;
      const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
      const int px = x - dir, py = y - dir;
      if (px >= 0 && px < w) {
        const int j = nn[static_cast<size_t>(y) * w + px];
        consider(i, x, y, j % w + dir * step, j / w, true);
      }
      if (py >= 0 && py < h) {
        const int j = nn[static_cast<size_t>(py) * w + x];
        consider(i, x, y, j % w, j / w + dir * step, true);
      }
      for (int r = std::max(w, h) / 2; r >= 1; r /= 2) {
        const int bx = nn[i] % w, by = nn[i] / w;
        consider(i, x, y, bx + rng.below(2 * r + 1) - r, by + rng.below(2 * r + 1) - r);
      }
    }
  }
  return nn;
}

// Integer-only kernels. State per pixel: int4 S = (x, y, node, 0), node = exemplar * (L + 1) + level;
// int4 R = (r, g, b, 0), the colour offset in 1/4096 of the sRGB range.
const char* kSource = R"CL(
uint gy_hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352dU; x ^= x >> 15; x *= 0x846ca68bU; x ^= x >> 16;
  return x;
}
uint gy_hash_pos(long x, long y, uint level, uint seed, uint lane) {
  const ulong ux = (ulong)x, uy = (ulong)y;
  uint h = gy_hash(seed ^ gy_hash(level * 0x9e3779b9U + lane * 0x85ebca6bU + 0x632be5abU));
  h = gy_hash(h ^ (uint)ux);
  h = gy_hash(h ^ (uint)(ux >> 32) ^ 0x27d4eb2fU);
  h = gy_hash(h ^ (uint)uy ^ 0x165667b1U);
  h = gy_hash(h ^ (uint)(uy >> 32) ^ 0xd3a2646cU);
  return h;
}
int gy_wrap(int x, int n) { int r = x % n; return r < 0 ? r + n : r; }

// Child q of parent q/2: node + 1 (next stack level), texel + floor(h (d - 1/2)) + jitter (LH05 with
// the child's spacing h); colour offset = bilinear mix of the 4 nearest parents (9, 3, 3, 1) / 16.
kernel void gy_upsample(global const int4* pS, global const int4* pR, int pw, long pox, long poy, int parent_zero,
                        global int4* S, global int4* R, int w, int h, long ox, long oy, int L, int ew, int eh,
                        int rq, uint seed, uint level) {
  const int i = get_global_id(0), j = get_global_id(1);
  if (i >= w || j >= h) return;
  const long qx = ox + i, qy = oy + j;
  int4 s = (int4)(0, 0, 0, 0);
  int4 r = (int4)(0, 0, 0, 0);
  if (!parent_zero) {
    const long px = qx >> 1, py = qy >> 1;
    const long ax = (qx & 1) ? px + 1 : px - 1, ay = (qy & 1) ? py + 1 : py - 1;
    s = pS[(py - poy) * pw + (px - pox)];
    const int4 r00 = pR[(py - poy) * pw + (px - pox)];
    const int4 r10 = pR[(py - poy) * pw + (ax - pox)];
    const int4 r01 = pR[(ay - poy) * pw + (px - pox)];
    const int4 r11 = pR[(ay - poy) * pw + (ax - pox)];
    r = (9 * r00 + 3 * r10 + 3 * r01 + r11 + 8) >> 4;
  }
  const int node = s.z + 1;
  const int k = node % (L + 1);
  const int spacing = 1 << (L - k);
  const int offx = (qx & 1) ? spacing / 2 : -((spacing + 1) / 2);
  const int offy = (qy & 1) ? spacing / 2 : -((spacing + 1) / 2);
  long jx = 0, jy = 0;
  if (rq > 0) {
    const int Hx = (int)(gy_hash_pos(qx, qy, level, seed, 0) % 131073U) - 65536;
    const int Hy = (int)(gy_hash_pos(qx, qy, level, seed, 1) % 131073U) - 65536;
    jx = ((long)spacing * rq * Hx + (1L << 31)) >> 32;
    jy = ((long)spacing * rq * Hy + (1L << 31)) >> 32;
  }
  S[(long)j * w + i] = (int4)(gy_wrap(s.x + offx + (int)jx, ew), gy_wrap(s.y + offy + (int)jy, eh), node, 0);
  R[(long)j * w + i] = (int4)(r.x, r.y, r.z, 0);
}

// One correction sub-pass over the pixels of parity (parx, pary) of the absolute coordinates.
// GT[t][k][c]: projected-feature change (shift 24) of a colour offset on tap t; GS = sum over taps.
kernel void gy_correct(global int4* S, global int4* R, int w, int h, long ox, long oy, int parx, int pary,
                       global const char* A, global const short* F, global const int* C,
                       global const int* LN, global const int* LT, global const short4* LO, int M,
                       constant int* P, constant long* GT, constant long* GS,
                       global const uchar* valid, global const uchar* adm, int nodes, global const uchar* tor, int L,
                       int ew, int eh, int kappa) {
  const int i = (int)((parx - (ox & 1)) & 1) + 2 * get_global_id(0);
  const int j = (int)((pary - (oy & 1)) & 1) + 2 * get_global_id(1);
  if (i >= w || j >= h) return;
  const long n = (long)ew * eh;
  const int tdx[5] = {0, -1, 1, -1, 1};
  const int tdy[5] = {0, -1, -1, 1, 1};
  const int odx[9] = {0, -1, 0, 1, -1, 1, -1, 0, 1};
  const int ody[9] = {0, -1, -1, -1, 0, 0, 1, 1, 1};
  const int4 me = S[(long)j * w + i];
  const int4 Rp = R[(long)j * w + i];
  // The synthesised neighbourhood seen in this pixel's colour frame (Han eq. 5.5): each tap's
  // appearance plus the change of its colour offset relative to this pixel's, projected.
  int proj[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  long off[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  for (int t = 0; t < 5; ++t) {
    const int ni = clamp(i + tdx[t], 0, w - 1), nj = clamp(j + tdy[t], 0, h - 1);
    const int4 c = S[(long)nj * w + ni];
    const int4 d = R[(long)nj * w + ni] - Rp;
    global const char* a = A + 8 * ((long)c.z * n + (long)c.y * ew + c.x);
    for (int e = 0; e < 8; ++e) {
      const int v = a[e];
      constant int* row = P + (t * 8 + e) * 8;
      for (int k = 0; k < 8; ++k) proj[k] += v * row[k];
    }
    if (d.x | d.y | d.z) {
      constant long* g = GT + t * 24;
      for (int k = 0; k < 8; ++k) off[k] += g[k * 3] * d.x + g[k * 3 + 1] * d.y + g[k * 3 + 2] * d.z;
    }
  }
  for (int k = 0; k < 8; ++k) proj[k] = (proj[k] >> 8) + (int)(off[k] >> 24);

  int4 best = me, bestR = Rp;
  int bestd = 0x7fffffff;
  // A pixel on a valid stack level keeps to it (or to one linked at the same scale, adm = 2); one that
  // must leave it (its finest level before the output level) takes any admissible level (adm >= 1).
  const int free_choice = valid[me.z];
  global const uchar* my_adm = adm + (long)me.z * nodes;
  const int need = free_choice ? 2 : 1;
  for (int q = 0; q < 9; ++q) {
    const int dx = odx[q], dy = ody[q];
    const int ni = clamp(i + dx, 0, w - 1), nj = clamp(j + dy, 0, h - 1);
    const int4 c = S[(long)nj * w + ni];
    const int4 rq = R[(long)nj * w + ni];
    // Candidates from this neighbour live in its colour frame: the target shifts by its offset.
    int target[8];
    const int4 d = rq - Rp;
    for (int k = 0; k < 8; ++k)
      target[k] = proj[k] - (int)((GS[k * 3] * d.x + GS[k * 3 + 1] * d.y + GS[k * 3 + 2] * d.z) >> 24);
    const long texel = (long)c.y * ew + c.x;
    for (int kk = 0; kk < 2 + M; ++kk) {
      int cn, idx;
      int4 b = (int4)(0, 0, 0, 0);
      if (kk < 2) {
        cn = c.z;
        idx = kk == 0 ? (int)texel : C[(long)cn * n + texel];
      } else {
        const long slot = (long)c.z * M + (kk - 2);
        cn = LN[slot];
        if (cn < 0) continue;
        idx = LT[slot * n + texel];
        const short4 o = LO[slot * n + texel];
        b = (int4)(o.x, o.y, o.z, 0);
      }
      if (!valid[cn] || my_adm[cn] < need) continue;
      const int cl = cn % (L + 1), ce = cn / (L + 1);
      const int sp = 1 << (L - cl);
      int ux = idx % ew - dx * sp, uy = idx / ew - dy * sp;
      if (!tor[ce]) {
        // A bounded exemplar: nothing that came across its border, and at the finer levels nothing
        // whose neighbourhood would leave it (as in the single-exemplar synthesis). A pixel that must
        // leave its stack level takes any candidate.
        const int margin = (free_choice && 8 * sp <= min(ew, eh)) ? sp : 0;
        if (ux < margin || ux >= ew - margin || uy < margin || uy >= eh - margin) continue;
      } else {
        ux = gy_wrap(ux, ew);
        uy = gy_wrap(uy, eh);
      }
      // The candidate's features, shifted by the link's colour offset (0 inside one exemplar).
      global const short* f = F + 8 * ((long)cn * n + (long)uy * ew + ux);
      int dist = 0;
      if (b.x | b.y | b.z) {
        for (int k = 0; k < 8; ++k) {
          const int e = target[k] - f[k] - (int)((GS[k * 3] * b.x + GS[k * 3 + 1] * b.y + GS[k * 3 + 2] * b.z) >> 24);
          dist += e * e;
        }
      } else {
        for (int k = 0; k < 8; ++k) { const int e = target[k] - f[k]; dist += e * e; }
      }
      if (kk >= 1) dist += (dist >> 8) * kappa;  // favour growing patches (LH05's kappa)
      if (dist < bestd) { bestd = dist; best = (int4)(ux, uy, cn, 0); bestR = (int4)(rq.x + b.x, rq.y + b.y, rq.z + b.z, 0); }
    }
  }
  S[(long)j * w + i] = best;
  R[(long)j * w + i] = bestR;
}
)CL";

struct Region {
  int64_t x = 0, y = 0;
  int w = 0, h = 0;
};

using detail::kMaxCoordinate;

template <typename... Args>
void launch2d(cl::Kernel& kernel, int gx, int gy, const Args&... args) {
  detail::launch2d("launching a graph synthesis kernel", kernel, gx, gy, args...);
}

}  // namespace

namespace {

constexpr uint32_t kGraphCacheVersion = 2;
constexpr uint32_t kGraphMagic = 0x47525048;  // "GRPH"

std::string graph_hash(const LoadedGraph& lg) {
  std::string key = fmt::format("proctex-graph v{} {}x{} e{}|", kGraphCacheVersion, lg.images[0].width,
                                lg.images[0].height, lg.images.size());
  for (const auto& e : lg.graph.edges) key += fmt::format("{},{},{};", e.from, e.to, e.r);
  for (size_t i = 0; i < lg.images.size(); ++i) {
    key += fmt::format("t{}|", int(lg.toroidal[i]));
    key.append(reinterpret_cast<const char*>(lg.images[i].pixels.data()), lg.images[i].pixels.size() * sizeof(float));
  }
  return fnv1a_hex(key);
}

using detail::read_vec;
using detail::write_vec;

// The cached analysis of a graph whose size, levels, exemplars and slots are already in `a`.
bool load_graph_cache(const std::filesystem::path& file, GraphAnalysis& a) {
  std::ifstream f(file, std::ios::binary);
  if (!f) return false;
  uint32_t head[2] = {0, 0};
  int32_t slots = -1;
  f.read(reinterpret_cast<char*>(head), sizeof head);
  f.read(reinterpret_cast<char*>(&slots), sizeof slots);
  if (!f || head[0] != kGraphMagic || head[1] != kGraphCacheVersion || slots < 0 || slots > 64) return false;
  a.slots = slots;
  const uint64_t n = static_cast<uint64_t>(a.width) * a.height, N = a.nodes(), M = static_cast<uint64_t>(slots);
  if (!read_vec(f, a.appearance, N * n * kDims) || !read_vec(f, a.feature, N * n * kDims) ||
      !read_vec(f, a.coherent, N * n) || !read_vec(f, a.link_node, N * M) || !read_vec(f, a.link_texel, N * M * n) ||
      !read_vec(f, a.link_offset, N * M * n * 4) || !read_vec(f, a.projection, uint64_t(kGraphNeighbourDims) * kDims) ||
      !read_vec(f, a.offset_response, uint64_t(kDims) * 3) || !read_vec(f, a.colour, N * n * 3))
    return false;
  for (int32_t c : a.coherent)
    if (c < 0 || static_cast<uint64_t>(c) >= n) return false;
  for (int32_t c : a.link_texel)
    if (c < 0 || static_cast<uint64_t>(c) >= n) return false;
  for (int32_t c : a.link_node)
    if (c < -1 || static_cast<uint64_t>(c + 1) > N) return false;
  char extra;
  return !f.read(&extra, 1);
}

void save_graph_cache(const std::filesystem::path& file, const GraphAnalysis& a) {
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  const auto tmp = file.string() + fmt::format(".tmp{}", static_cast<long>(::getpid()));
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return;  // the cache is an optimisation
    const uint32_t head[2] = {kGraphMagic, kGraphCacheVersion};
    const int32_t slots = a.slots;
    f.write(reinterpret_cast<const char*>(head), sizeof head);
    f.write(reinterpret_cast<const char*>(&slots), sizeof slots);
    write_vec(f, a.appearance);
    write_vec(f, a.feature);
    write_vec(f, a.coherent);
    write_vec(f, a.link_node);
    write_vec(f, a.link_texel);
    write_vec(f, a.link_offset);
    write_vec(f, a.projection);
    write_vec(f, a.offset_response);
    write_vec(f, a.colour);
    if (!f) {
      f.close();
      std::filesystem::remove(tmp, ec);
      return;
    }
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) std::filesystem::remove(tmp, ec);
}

}  // namespace

GraphAnalysis analyse_graph_cached(const LoadedGraph& lg, const std::filesystem::path& cache_dir) {
  if (cache_dir.empty()) return analyse_graph(lg);
  GraphAnalysis a;
  a.width = lg.images[0].width;
  a.height = lg.images[0].height;
  a.levels = level_count(a.width, a.height);
  a.exemplars = static_cast<int>(lg.images.size());
  a.toroidal = lg.toroidal;
  a.hash = graph_hash(lg);
  const auto file = cache_dir / ("graph-" + a.hash + ".bin");
  if (load_graph_cache(file, a)) {
    a.from_cache = true;
    return a;
  }
  GraphAnalysis fresh = analyse_graph(lg);
  save_graph_cache(file, fresh);
  return fresh;
}

LoadedGraph load_graph(ExemplarGraph graph) {
  LoadedGraph g;
  for (size_t i = 0; i < graph.exemplars.size(); ++i) {
    const auto& e = graph.exemplars[i];
    Image im = load_exemplar_image(e.image);
    if (i > 0 && (im.width != g.images[0].width || im.height != g.images[0].height))
      throw Error(fmt::format("graph '{}': exemplar {} '{}' is {}x{} but the root is {}x{}", graph.name, i,
                              e.image.filename().string(), im.width, im.height, g.images[0].width,
                              g.images[0].height),
                  "all exemplars of a graph must have the same size; resize or crop them");
    bool tor = e.tiles == "yes";
    if (e.tiles == "auto") {
      Exemplar ex;
      ex.colour = im;
      tor = tiles_seamlessly(ex);
    }
    g.toroidal.push_back(tor ? 1 : 0);
    g.images.push_back(std::move(im));
  }
  validate_graph(graph, level_count(g.images[0].width, g.images[0].height));
  g.graph = std::move(graph);
  return g;
}

LoadedGraph load_graph(const std::filesystem::path& file) { return load_graph(parse_graph(file)); }

int graph_levels(const LoadedGraph& g) { return level_count(g.images.at(0).width, g.images.at(0).height); }

GraphAnalysis analyse_graph(const LoadedGraph& lg) {
  const auto start = std::chrono::steady_clock::now();
  GraphAnalysis a;
  a.width = lg.images[0].width;
  a.height = lg.images[0].height;
  a.levels = level_count(a.width, a.height);
  a.exemplars = static_cast<int>(lg.images.size());
  a.toroidal = lg.toroidal;
  const int w = a.width, h = a.height, L = a.levels;
  const size_t n = static_cast<size_t>(w) * h;
  const size_t N = a.nodes();

  a.hash = graph_hash(lg);

  // Gaussian stacks of the sRGB-encoded colours; node n = i * (L + 1) + k.
  std::vector<std::vector<float>> planes(N);  // planar 3 x n per node
  parallel_for(a.exemplars, 0, [&](int i) {
    std::vector<float> planar(3 * n);
    const auto& px = lg.images[i].pixels;
    for (size_t t = 0; t < n; ++t)
      for (int c = 0; c < 3; ++c) planar[c * n + t] = linear_to_srgb(std::clamp(px[3 * t + c], 0.0f, 1.0f));
    auto stack = colour_stack(planar, L, Sampler{w, h, lg.toroidal[i] != 0});
    for (int k = 0; k <= L; ++k) planes[i * (L + 1) + k] = std::move(stack[k]);
  });
  a.colour.resize(N * n * 3);
  for (size_t nd = 0; nd < N; ++nd)
    for (size_t t = 0; t < n; ++t)
      for (int c = 0; c < 3; ++c) a.colour[(nd * n + t) * 3 + c] = planes[nd][c * n + t];

  auto sampler_of = [&](size_t nd) { return Sampler{w, h, lg.toroidal[nd / (L + 1)] != 0}; };
  float tapw[kColourTaps];
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) tapw[(dy + 2) * 5 + dx + 2] = std::sqrt(std::exp(-(dx * dx + dy * dy) / 4.5f));
  auto gather = [&](size_t nd, size_t t, double* row) {
    const Sampler s = sampler_of(nd);
    const int sp = 1 << (L - static_cast<int>(nd % (L + 1)));
    const int x = static_cast<int>(t % w), y = static_cast<int>(t / w);
    const auto& pl = planes[nd];
    int k = 0;
    for (int dy = -2; dy <= 2; ++dy) {
      const int yy = s.iy(y + dy * sp);
      for (int dx = -2; dx <= 2; ++dx) {
        const size_t u = static_cast<size_t>(yy) * w + s.ix(x + dx * sp);
        const float wt = tapw[(dy + 2) * 5 + dx + 2];
        for (int c = 0; c < 3; ++c) row[k++] = wt * pl[c * n + u];
      }
    }
  };
  // One appearance space for every stack level of every exemplar: covariance of a regular sample.
  const size_t per_node = std::max<size_t>(256, 32768 / N);
  const size_t step = std::max<size_t>(1, n / per_node);
  Eigen::VectorXd mean = Eigen::VectorXd::Zero(kAppIn);
  Eigen::MatrixXd second = Eigen::MatrixXd::Zero(kAppIn, kAppIn);
  size_t rows = 0;
  {
    Eigen::VectorXd v(kAppIn);
    for (size_t nd = 0; nd < N; ++nd)
      for (size_t t = 0; t < n; t += step) {
        gather(nd, t, v.data());
        mean += v;
        second.selfadjointView<Eigen::Lower>().rankUpdate(v);
        ++rows;
      }
  }
  mean /= double(rows);
  Eigen::MatrixXd cov = second.selfadjointView<Eigen::Lower>();
  cov = cov / double(rows) - mean * mean.transpose();
  double top = 0;
  const Eigen::MatrixXd axes = principal_axes(cov, kDims, top);
  const double scale = top > 1e-12 ? 127.0 / (3.5 * std::sqrt(top)) : 0.0;
  a.appearance.resize(N * n * kDims);
  parallel_for(static_cast<int>(N), 0, [&](int nd) {
    Eigen::VectorXd v(kAppIn);
    for (size_t t = 0; t < n; ++t) {
      gather(nd, t, v.data());
      v -= mean;
      for (int d = 0; d < kDims; ++d) {
        const double p = std::clamp(std::round(axes.col(d).dot(v) * scale), -127.0, 127.0);
        a.appearance[(nd * n + t) * kDims + d] = static_cast<int8_t>(p);
      }
    }
  });
  // Appearance change per unit of colour offset (a constant added to every tap), shift 16 with
  // offsets in 1/4096: AR = 16 * scale * sum_taps w_tap axis(tap, c).
  a.offset_response.resize(kDims * 3);
  for (int d = 0; d < kDims; ++d)
    for (int c = 0; c < 3; ++c) {
      double s = 0;
      for (int t = 0; t < kColourTaps; ++t) s += tapw[t] * axes(t * 3 + c, d);
      a.offset_response[d * 3 + c] = static_cast<int32_t>(std::lround(16.0 * scale * s));
    }

  // Matching neighbourhood: the appearance at the centre and the 4 diagonals at the level's spacing.
  const int tdx[kTaps] = {0, -1, 1, -1, 1}, tdy[kTaps] = {0, -1, -1, 1, 1};
  auto taps = [&](size_t nd, size_t t, int8_t* out) {
    const Sampler s = sampler_of(nd);
    const int sp = 1 << (L - static_cast<int>(nd % (L + 1)));
    const int x = static_cast<int>(t % w), y = static_cast<int>(t / w);
    for (int k = 0; k < kTaps; ++k) {
      const size_t u = static_cast<size_t>(s.iy(y + tdy[k] * sp)) * w + s.ix(x + tdx[k] * sp);
      std::memcpy(out + k * kDims, &a.appearance[(nd * n + u) * kDims], kDims);
    }
  };
  {
    Eigen::VectorXd m2 = Eigen::VectorXd::Zero(kGraphNeighbourDims);
    Eigen::MatrixXd s2 = Eigen::MatrixXd::Zero(kGraphNeighbourDims, kGraphNeighbourDims);
    size_t r2 = 0;
    int8_t buf[kGraphNeighbourDims];
    Eigen::VectorXd v(kGraphNeighbourDims);
    for (size_t nd = 0; nd < N; ++nd)
      for (size_t t = 0; t < n; t += step) {
        taps(nd, t, buf);
        for (int d = 0; d < kGraphNeighbourDims; ++d) v(d) = buf[d];
        m2 += v;
        s2.selfadjointView<Eigen::Lower>().rankUpdate(v);
        ++r2;
      }
    m2 /= double(r2);
    Eigen::MatrixXd c2 = s2.selfadjointView<Eigen::Lower>();
    c2 = c2 / double(r2) - m2 * m2.transpose();
    double top2 = 0;
    const Eigen::MatrixXd ax2 = principal_axes(c2, kDims, top2);
    a.projection.resize(kGraphNeighbourDims * kDims);
    for (int d = 0; d < kGraphNeighbourDims; ++d)
      for (int k = 0; k < kDims; ++k)
        a.projection[d * kDims + k] = static_cast<int32_t>(std::lround(ax2(d, k) * (1 << kProjectionShift)));
  }
  a.feature.resize(N * n * kDims);
  parallel_for(static_cast<int>(N), 0, [&](int nd) {
    int8_t buf[kGraphNeighbourDims];
    for (size_t t = 0; t < n; ++t) {
      taps(nd, t, buf);
      for (int k = 0; k < kDims; ++k) {
        int32_t acc = 0;
        for (int d = 0; d < kGraphNeighbourDims; ++d) acc += int32_t(buf[d]) * a.projection[d * kDims + k];
        a.feature[(nd * n + t) * kDims + k] = static_cast<int16_t>(acc >> kProjectionShift);
      }
    }
  });

  // Which nodes can ever appear (any zoom up to the schedule's reach): only those are matched.
  std::vector<unsigned char> used(N, 0);
  for (int t = 0; t <= L + static_cast<int>(N); ++t)
    for (const auto& s : superexemplar_level(lg.graph, L, t)) used[s.exemplar * (L + 1) + s.level] = 1;
  for (size_t nd = 0; nd < N; ++nd)
    if (nd % (L + 1) == static_cast<size_t>(L) && used[nd - 1]) used[nd] = 1;  // upsampled finest levels

  // k-coherence (k = 2): a similar texel at least 5% of the exemplar away, on the same stack level.
  const int sep = std::max(2, static_cast<int>(std::lround(0.05 * std::max(w, h))));
  a.coherent.assign(N * n, 0);
  parallel_for(static_cast<int>(N), 0, [&](int nd) {
    if (!used[nd]) {
      for (size_t t = 0; t < n; ++t) a.coherent[nd * n + t] = static_cast<int32_t>(t);
      return;
    }
    const int16_t* f = a.feature.data() + nd * n * kDims;
    auto dist = [&](size_t p, size_t q) {
      int64_t d = 0;
      for (int k = 0; k < kDims; ++k) {
        const int64_t e = int64_t(f[p * kDims + k]) - f[q * kDims + k];
        d += e * e;
      }
      return d;
    };
    const auto nn = patch_match(w, h, lg.toroidal[nd / (L + 1)] != 0, 1, sep, 0x5eed0000u + nd, dist);
    std::copy(nn.begin(), nn.end(), a.coherent.begin() + nd * n);
  });

  // Links along the explicit edges: slot s of exemplar i = its s-th explicit out edge.
  std::vector<std::vector<GraphEdge>> out(a.exemplars);
  for (const auto& e : lg.graph.edges) out[e.from].push_back(e);
  for (const auto& o : out) a.slots = std::max(a.slots, static_cast<int>(o.size()));
  const int M = a.slots;
  a.link_node.assign(N * M, -1);
  for (size_t nd = 0; nd < N; ++nd) {
    const int i = static_cast<int>(nd / (L + 1)), k = static_cast<int>(nd % (L + 1));
    for (size_t s = 0; s < out[i].size(); ++s) {
      const int l = k - out[i][s].r;
      if (l >= 0 && used[nd]) a.link_node[nd * M + s] = out[i][s].to * (L + 1) + l;
    }
  }
  // Local mean colour (25 taps, Han's b) per texel of every node, for the offsets and the
  // offset-invariant matching between different exemplars.
  std::vector<float> local_mean(N * n * 3, 0.0f);
  parallel_for(static_cast<int>(N), 0, [&](int nd) {
    if (!used[nd]) return;
    const Sampler s = sampler_of(nd);
    const int sp = 1 << (L - static_cast<int>(nd % (L + 1)));
    for (size_t t = 0; t < n; ++t) {
      const int x = static_cast<int>(t % w), y = static_cast<int>(t / w);
      double acc[3] = {0, 0, 0};
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const size_t u = static_cast<size_t>(s.iy(y + dy * sp)) * w + s.ix(x + dx * sp);
          for (int c = 0; c < 3; ++c) acc[c] += planes[nd][c * n + u];
        }
      for (int c = 0; c < 3; ++c) local_mean[(nd * n + t) * 3 + c] = static_cast<float>(acc[c] / kColourTaps);
    }
  });
  // The feature change per unit colour (sRGB 1.0): G = PS^T AR / 16 (AR is per 1/4096, shift 16).
  double G[kDims][3];
  for (int k = 0; k < kDims; ++k)
    for (int c = 0; c < 3; ++c) {
      double acc = 0;
      for (int d = 0; d < kDims; ++d) {
        double ps = 0;
        for (int t = 0; t < kTaps; ++t) ps += a.projection[(t * kDims + d) * kDims + k];
        acc += a.offset_response[d * 3 + c] / 16.0 * ps / (1 << kProjectionShift);
      }
      G[k][c] = acc;
    }
  std::vector<float> mean_free(N * n * kDims, 0.0f);
  parallel_for(static_cast<int>(N), 0, [&](int nd) {
    if (!used[nd]) return;
    for (size_t t = 0; t < n; ++t)
      for (int k = 0; k < kDims; ++k) {
        double v = a.feature[(nd * n + t) * kDims + k];
        for (int c = 0; c < 3; ++c) v -= G[k][c] * local_mean[(nd * n + t) * 3 + c];
        mean_free[(nd * n + t) * kDims + k] = static_cast<float>(v);
      }
  });
  a.link_texel.assign(N * M * n, 0);
  a.link_offset.assign(N * M * n * 4, 0);
  parallel_for(static_cast<int>(N * M), 0, [&](int job) {
    const size_t nd = job / M, s = job % M;
    const int dst = a.link_node[nd * M + s];
    if (dst < 0) return;
    const int i = static_cast<int>(nd / (L + 1)), j = dst / (L + 1);
    const int r = out[i][s].r;
    const int16_t* fa = a.feature.data() + nd * n * kDims;
    const int16_t* fb = a.feature.data() + static_cast<size_t>(dst) * n * kDims;
    std::vector<int32_t> nn;
    const uint64_t seed = 0x11a4000000ull + job;
    if (i == j) {
      // Inside one exemplar (a self edge with r > 0): plain matching, no offset (Han: b = 0).
      auto dist = [&](size_t p, size_t q) {
        int64_t d = 0;
        for (int k = 0; k < kDims; ++k) {
          const int64_t e = int64_t(fa[p * kDims + k]) - fb[q * kDims + k];
          d += e * e;
        }
        return d;
      };
      nn = patch_match(w, h, lg.toroidal[j] != 0, 1 << r, 0, seed, dist, kLinkBias);
    } else {
      // Between exemplars: match the structure whatever the mean colour (the offset b repairs it):
      // |fa - (fb + G (ma - mb))| = |(fa - G ma) - (fb - G mb)|, the mean-free features.
      const float* ma = mean_free.data() + nd * n * kDims;
      const float* mb = mean_free.data() + static_cast<size_t>(dst) * n * kDims;
      auto dist = [&](size_t p, size_t q) {
        float d = 0;
        for (int k = 0; k < kDims; ++k) {
          const float e = ma[p * kDims + k] - mb[q * kDims + k];
          d += e * e;
        }
        return static_cast<int64_t>(d * 16.0f);
      };
      nn = patch_match(w, h, lg.toroidal[j] != 0, 1 << r, 0, seed, dist, kLinkBias);
    }
    const size_t base = (nd * M + s) * n;
    std::copy(nn.begin(), nn.end(), a.link_texel.begin() + base);
    if (i != j) {
      const float* ma = local_mean.data() + nd * n * 3;
      const float* mb = local_mean.data() + static_cast<size_t>(dst) * n * 3;
      for (size_t t = 0; t < n; ++t)
        for (int c = 0; c < 3; ++c) {
          const double b = (ma[t * 3 + c] - mb[static_cast<size_t>(nn[t]) * 3 + c]) * kOffsetUnits;
          a.link_offset[(base + t) * 4 + c] = static_cast<int16_t>(std::clamp<double>(std::lround(b), -32767, 32767));
        }
    }
  });
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return a;
}

struct GraphSynthesizer::Device {
  cl::Program program;
  cl::Kernel upsample, correct;
  cl::Buffer appearance, feature, coherent, link_node, link_texel, link_offset, projection,
      offset_tap, offset_sum, toroidal, admissible;
};

GraphSynthesizer::GraphSynthesizer(const LoadedGraph& graph, const GraphAnalysis& a)
    : graph_(graph), analysis_(a), device_(std::make_unique<Device>()) {
  auto& rt = ocl::Runtime::instance();
  auto& d = *device_;
  d.program = rt.program(kSource, "-cl-std=CL1.2");
  ocl::with_cl_errors("creating the graph synthesis kernels", [&] {
    d.upsample = cl::Kernel(d.program, "gy_upsample");
    d.correct = cl::Kernel(d.program, "gy_correct");
    return 0;
  });
  d.appearance = ocl::upload(a.appearance);
  d.feature = ocl::upload(a.feature);
  d.coherent = ocl::upload(a.coherent);
  d.link_node = ocl::upload(a.link_node);
  d.link_texel = ocl::upload(a.link_texel);
  d.link_offset = ocl::upload(a.link_offset);
  d.projection = ocl::upload(a.projection);
  // GT[t][k][c] = sum_d P[t][d][k] AR[d][c]: the projected-feature change of a colour offset on tap t
  // (shift 8 of P + shift 16 of AR); GS = the sum over the taps (an offset on the whole neighbourhood).
  std::vector<cl_long> gt(kTaps * kDims * 3, 0), gs(kDims * 3, 0);
  for (int t = 0; t < kTaps; ++t)
    for (int k = 0; k < kDims; ++k)
      for (int c = 0; c < 3; ++c) {
        int64_t acc = 0;
        for (int dd = 0; dd < kDims; ++dd)
          acc += int64_t(a.projection[(t * kDims + dd) * kDims + k]) * a.offset_response[dd * 3 + c];
        gt[(t * kDims + k) * 3 + c] = acc;
        gs[k * 3 + c] += acc;
      }
  d.offset_tap = ocl::upload(gt);
  d.offset_sum = ocl::upload(gs);
  d.toroidal = ocl::upload(a.toroidal);
  // adm[m][n]: 2 = n is m itself or linked by a scale-1 edge (same level), 1 = n is admissible for m
  // (Han's A(m), the finest level included: the schedule's `valid` excludes it before the output).
  const int L = a.levels;
  const size_t N = a.nodes();
  std::vector<unsigned char> adm(N * N, 0);
  for (size_t m = 0; m < N; ++m) {
    const StackLevel from{static_cast<int>(m / (L + 1)), static_cast<int>(m % (L + 1))};
    for (const auto& s : admissible(graph.graph, L, from, true)) {
      const size_t n = static_cast<size_t>(s.exemplar) * (L + 1) + s.level;
      adm[m * N + n] = s.level == from.level ? 2 : 1;
    }
  }
  d.admissible = ocl::upload(adm);
}

GraphSynthesizer::~GraphSynthesizer() = default;

std::vector<GraphPixel> GraphSynthesizer::synthesise(const Window& win, const SynthOptions& o, int zoom) {
  const GraphAnalysis& a = analysis_;
  if (!o.jitter_map.empty() || !o.pastes.empty() || o.period_x > 0 || o.period_y > 0)
    throw UsageError("--jitter-map, --paste and --tileable are not available with --graph");
  if (o.randomness.empty()) throw UsageError("--randomness needs at least one value");
  for (float r : o.randomness)
    if (!(r >= 0.0f && r <= 4.0f))
      throw UsageError(fmt::format("randomness {} is outside [0, 4]", r), "0 = tiling, 0.5 = default, 1 = strong");
  // One number of correction passes for every level of a graph synthesis (its windows are padded
  // once): the last value of the per-level list, i.e. the fine levels' value.
  if (o.passes.empty()) throw UsageError("--passes needs at least one value");
  const int passes = o.passes.back();
  if (passes < 0 || passes > 8) throw UsageError("--passes must be in [0, 8]");
  if (zoom < 0 || zoom > kMaxGraphZoom)
    throw UsageError(fmt::format("--zoom {} is out of range", zoom), fmt::format("use 0..{}", kMaxGraphZoom));
  if (win.width <= 0 || win.height <= 0) throw UsageError("the window must have a positive width and height");
  if (std::llabs(win.x) > kMaxCoordinate || std::llabs(win.y) > kMaxCoordinate)
    throw UsageError("the window offset is too large", "offsets must lie within +-2^60");
  const int L = a.levels;
  const LevelSchedule schedule = level_schedule(graph_.graph, L, zoom);
  const int T = schedule.depth;
  if (static_cast<int>(o.randomness.size()) > T)
    throw UsageError(fmt::format("--randomness has {} values but this synthesis has {} levels", o.randomness.size(), T),
                     "give one value, or at most one per level, coarse to fine");

  const int pad = 4 * passes + 2;
  std::vector<Region> region(T + 1);
  region[T] = {win.x - pad, win.y - pad, win.width + 2 * pad, win.height + 2 * pad};
  for (int t = T; t > 1; --t) {
    const Region& r = region[t];
    const int64_t px0 = r.x >> 1, py0 = r.y >> 1;
    const int64_t px1 = (r.x + r.w - 1) >> 1, py1 = (r.y + r.h - 1) >> 1;
    region[t - 1] = {px0 - pad, py0 - pad, static_cast<int>(px1 - px0 + 1) + 2 * pad,
                     static_cast<int>(py1 - py0 + 1) + 2 * pad};
  }
  auto& dev = *device_;
  auto& ctx = ocl::Runtime::instance().context();
  cl::Buffer pS = ocl::output_buffer(sizeof(cl_int4)), pR = ocl::output_buffer(sizeof(cl_int4));
  Region parent_region;
  bool parent_zero = true;
  for (int t = 1; t <= T; ++t) {
    const Region& r = region[t];
    const size_t count = static_cast<size_t>(r.w) * r.h;
    cl::Buffer S, R;
    ocl::with_cl_errors("allocating a graph synthesis level", [&] {
      S = cl::Buffer(ctx, CL_MEM_READ_WRITE, count * sizeof(cl_int4));
      R = cl::Buffer(ctx, CL_MEM_READ_WRITE, count * sizeof(cl_int4));
      return 0;
    });
    const size_t ri = static_cast<size_t>(std::min<int>(t - 1, static_cast<int>(o.randomness.size()) - 1));
    const cl_int rq = static_cast<cl_int>(std::lround(o.randomness[ri] * 65536.0));
    launch2d(dev.upsample, r.w, r.h, pS, pR, static_cast<cl_int>(parent_region.w),
             static_cast<cl_long>(parent_region.x), static_cast<cl_long>(parent_region.y),
             static_cast<cl_int>(parent_zero ? 1 : 0), S, R, static_cast<cl_int>(r.w), static_cast<cl_int>(r.h),
             static_cast<cl_long>(r.x), static_cast<cl_long>(r.y), static_cast<cl_int>(L),
             static_cast<cl_int>(a.width), static_cast<cl_int>(a.height), rq, static_cast<cl_uint>(o.seed),
             static_cast<cl_uint>(t));
    cl::Buffer valid = ocl::upload(schedule.valid[t]);
    for (int pass = 0; pass < passes; ++pass) {
      for (int sub = 0; sub < 4; ++sub) {
        launch2d(dev.correct, (r.w + 1) / 2, (r.h + 1) / 2, S, R, static_cast<cl_int>(r.w), static_cast<cl_int>(r.h),
                 static_cast<cl_long>(r.x), static_cast<cl_long>(r.y), static_cast<cl_int>(sub & 1),
                 static_cast<cl_int>(sub >> 1), dev.appearance, dev.feature, dev.coherent, dev.link_node,
                 dev.link_texel, dev.link_offset, static_cast<cl_int>(a.slots), dev.projection, dev.offset_tap,
                 dev.offset_sum, valid, dev.admissible, static_cast<cl_int>(a.nodes()), dev.toroidal,
                 static_cast<cl_int>(L), static_cast<cl_int>(a.width),
                 static_cast<cl_int>(a.height), static_cast<cl_int>(std::lround(o.kappa * 256)));
      }
    }
    pS = S;
    pR = R;
    parent_region = r;
    parent_zero = false;
  }
  const Region& r = region[T];
  std::vector<cl_int4> s(static_cast<size_t>(win.width) * win.height), rr(s.size());
  for (int y = 0; y < win.height; ++y) {
    const size_t off = static_cast<size_t>(y + pad) * r.w + pad;
    ocl::download_async(pS, off, static_cast<size_t>(win.width), s.data() + static_cast<size_t>(y) * win.width);
    ocl::download_async(pR, off, static_cast<size_t>(win.width), rr.data() + static_cast<size_t>(y) * win.width);
  }
  ocl::finish();
  std::vector<GraphPixel> out(s.size());
  for (size_t i = 0; i < s.size(); ++i) {
    const int node = s[i].s[2];
    out[i] = {s[i].s[0], s[i].s[1], node / (L + 1), node % (L + 1), rr[i].s[0], rr[i].s[1], rr[i].s[2]};
  }
  return out;
}

std::vector<float> GraphSynthesizer::colours(const std::vector<GraphPixel>& px) const {
  const GraphAnalysis& a = analysis_;
  const size_t n = static_cast<size_t>(a.width) * a.height;
  std::vector<float> out(px.size() * 3);
  for (size_t i = 0; i < px.size(); ++i) {
    const auto& p = px[i];
    const size_t node = static_cast<size_t>(p.exemplar) * (a.levels + 1) + p.level;
    const float* c = &a.colour[(node * n + static_cast<size_t>(p.y) * a.width + p.x) * 3];
    const int32_t off[3] = {p.r, p.g, p.b};
    for (int k = 0; k < 3; ++k)
      out[3 * i + k] = std::clamp(c[k] + static_cast<float>(off[k]) / kOffsetUnits, 0.0f, 1.0f);
  }
  return out;
}

}  // namespace proctex::synth
