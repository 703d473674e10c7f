// RGBN synthesis with synth/'s exemplar synthesiser (rgbn/synth.h, "exemplar_*"): the RGBN's
// albedo is the exemplar colour, its normals an exemplar normal map; synth/ gives exemplar
// coordinates, and every output pixel copies the (albedo, normal) pair at its coordinate.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "core/error.h"
#include "image/image.h"
#include "rgbn/synth.h"
#include "synth/analysis.h"
#include "synth/exemplar.h"
#include "synth/synthesis.h"

namespace proctex::rgbn {
namespace {

synth::Exemplar to_exemplar(const Rgbn& ex, float normal_weight) {
  if (ex.width < synth::kMinExemplarSide || ex.height < synth::kMinExemplarSide ||
      ex.width > synth::kMaxExemplarSide || ex.height > synth::kMaxExemplarSide)
    throw UsageError("the example RGBN is " + std::to_string(ex.width) + "x" + std::to_string(ex.height) +
                         ": the synth method takes examples of " + std::to_string(synth::kMinExemplarSide) + " to " +
                         std::to_string(synth::kMaxExemplarSide) + " pixels a side",
                     "crop the example, or use --method jump");
  if (!(normal_weight >= 0 && normal_weight <= 10))
    throw UsageError("the normal weight must be in [0, 10]", "e.g. --normal-weight 1");
  synth::Exemplar e;
  e.name = "rgbn example";
  e.colour = Image(ex.width, ex.height);
  std::copy(ex.albedo.begin(), ex.albedo.end(), e.colour.pixels.begin());
  for (float& v : e.colour.pixels) v = std::clamp(v, 0.0f, 1.0f);
  synth::ExemplarMap m;
  m.name = "normals";
  m.kind = synth::MapKind::Normal;
  // synth/ reads a normal map as it is stored in an 8/16-bit file, (n + 1) / 2, linearised on
  // load: encode it the same way so that it decodes back to n.
  m.image = Image(ex.width, ex.height);
  for (size_t i = 0; i < ex.normal.size(); ++i) m.image.pixels[i] = srgb_to_linear((ex.normal[i] + 1.0f) * 0.5f);
  e.maps.push_back(std::move(m));
  e.map_weight = normal_weight;
  synth::validate(e);
  return e;
}

struct Prepared {
  synth::Exemplar exemplar;
  synth::Analysis analysis;
  synth::SynthOptions options;
};

std::unique_ptr<Prepared> prepare(const Rgbn& ex, const ExemplarSynthOptions& o) {
  if (o.xi >= 90 || std::isnan(o.xi)) throw UsageError("--xi must be in [0, 90) degrees", "e.g. --xi 10");
  auto p = std::make_unique<Prepared>();
  p->exemplar = to_exemplar(ex, o.normal_weight);
  p->analysis = synth::analyse_cached(p->exemplar, {}, o.cache_dir);
  p->options.seed = uint32_t(o.seed);
  if (!o.randomness.empty()) p->options.randomness = o.randomness;
  p->options.passes = {o.passes};  // every level (rgbn synth --passes); the finest as synth/'s default
  p->options.kappa = o.coherence;
  synth::check_options(p->analysis, p->options);
  return p;
}

void fill_result_meta(ExemplarSynthResult& r, const Prepared& p) {
  r.levels = p.analysis.levels;
  r.example_tiles = p.analysis.toroidal;
  r.analysis_cached = p.analysis.from_cache;
  r.analysis_seconds = p.analysis.seconds;
}

}  // namespace

ExemplarSynthResult exemplar_synthesize(const Rgbn& ex, int w, int h, const ExemplarSynthOptions& o) {
  check_dimensions(w, h);
  const auto p = prepare(ex, o);
  synth::Synthesizer synthesizer(p->analysis);
  ExemplarSynthResult r;
  fill_result_meta(r, *p);
  r.image = Rgbn(w, h);
  r.source.assign(r.image.size(), -1);
  // Strips of rows (synth/ is spatially deterministic: a strip equals that part of the whole).
  const int rows = std::max(1, int((size_t(1) << 22) / size_t(w)));
  for (int y0 = 0; y0 < h; y0 += rows) {
    const int sh = std::min(rows, h - y0);
    const std::vector<int32_t> c = synthesizer.synthesise({0, y0, w, sh}, p->options);
    for (size_t i = 0; i < size_t(w) * sh; ++i) {
      const size_t q = size_t(y0) * w + i;
      const int s = c[2 * i + 1] * ex.width + c[2 * i];
      r.source[q] = s;
      std::copy_n(&ex.albedo[3 * size_t(s)], 3, &r.image.albedo[3 * q]);
      std::copy_n(&ex.normal[3 * size_t(s)], 3, &r.image.normal[3 * q]);
    }
    if (o.progress) o.progress(double(y0 + sh) / h);
  }
  r.visited = r.image.size();
  if (o.xi >= 0) detail::saturate_synthesised(r.image, Rgbn(w, h), r.source, o.xi);
  return r;
}

ExemplarSynthResult exemplar_fill(const Rgbn& ex, const Rgbn& target, const Mask& mask, const ExemplarSynthOptions& o) {
  if (mask.size() != target.size())
    throw Error("the fill mask is not the size of the target", "give a mask of the same size");
  if (o.windows < 1 || o.windows > 1024) throw UsageError("--windows must be in [1, 1024]", "e.g. --windows 16");
  if (o.ring < 1 || o.ring > 64) throw UsageError("--ring must be in [1, 64] pixels", "e.g. --ring 4");
  const int W = target.width, H = target.height;
  int x0 = W, y0 = H, x1 = -1, y1 = -1;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (mask[size_t(y) * W + x] > 0) x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  const auto p = prepare(ex, o);
  ExemplarSynthResult r;
  fill_result_meta(r, *p);
  r.image = target;
  r.source.assign(target.size(), -1);
  if (x1 < 0) return r;  // nothing to fill
  // The window: the region's bounding box grown by the ring, clipped to the image.
  const int R = o.ring;
  const int wx0 = std::max(0, x0 - R), wy0 = std::max(0, y0 - R), wx1 = std::min(W - 1, x1 + R),
            wy1 = std::min(H - 1, y1 + R);
  const int ww = wx1 - wx0 + 1, wh = wy1 - wy0 + 1;
  // Ring pixels: outside the region, within R pixels (Chebyshev) of it.
  std::vector<int> ring;
  for (int y = wy0; y <= wy1; ++y)
    for (int x = wx0; x <= wx1; ++x) {
      if (mask[size_t(y) * W + x] > 0) continue;
      bool near = false;
      for (int j = -R; j <= R && !near; ++j)
        for (int i = -R; i <= R && !near; ++i) {
          const int xx = x + i, yy = y + j;
          near = xx >= 0 && yy >= 0 && xx < W && yy < H && mask[size_t(yy) * W + xx] > 0;
        }
      if (near) ring.push_back(y * W + x);
    }
  Rgbn eb, tb;
  if (o.compose) eb = base_normals(ex, o.base_sigma), tb = base_normals(target, o.base_sigma);
  // The normal a synthesised pixel p with example source s gets.
  auto normal_of = [&](int s, size_t q) -> Vec3 {
    if (!o.compose) return {ex.normal[3 * size_t(s)], ex.normal[3 * size_t(s) + 1], ex.normal[3 * size_t(s) + 2]};
    return compose_detail(ex, eb, s, {tb.normal[3 * q], tb.normal[3 * q + 1], tb.normal[3 * q + 2]});
  };
  synth::Synthesizer synthesizer(p->analysis);
  std::mt19937_64 rng(o.seed ^ 0x5eed5eedull);
  std::uniform_int_distribution<int64_t> offset(-(int64_t(1) << 24), int64_t(1) << 24);
  // Scoring a window needs only its ring pixels: synth/ is spatially deterministic (a window equals
  // that region of any larger synthesis), so only rectangles of the 64^2 tiles that hold ring pixels
  // are synthesised per candidate, when they cover at most half the window (large regions); the
  // whole window is synthesised once, for the best offset.
  constexpr int kTile = 64;
  const int tx_n = (ww + kTile - 1) / kTile, ty_n = (wh + kTile - 1) / kTile;
  std::vector<std::vector<size_t>> tile_ring(size_t(tx_n) * ty_n);  // indices into `ring`
  for (size_t k = 0; k < ring.size(); ++k) {
    const int x = ring[k] % W - wx0, y = ring[k] / W - wy0;
    tile_ring[size_t(y / kTile) * tx_n + x / kTile].push_back(k);
  }
  // The ring's tiles merged into few rectangles (every synthesise() call costs a fixed number of
  // kernel launches): runs of tiles along each band of rows, then runs with the same extent in
  // consecutive bands joined (a rectangular region's ring becomes 4 strips).
  struct TileRect {
    int tx0, tx1, ty0, ty1;  // inclusive tile ranges
  };
  std::vector<TileRect> rects;
  std::map<std::pair<int, int>, size_t> open;
  for (int ty = 0; ty < ty_n; ++ty) {
    std::map<std::pair<int, int>, size_t> next_open;
    for (int tx = 0; tx < tx_n;) {
      if (tile_ring[size_t(ty) * tx_n + tx].empty()) {
        ++tx;
        continue;
      }
      int end = tx;
      while (end + 1 < tx_n && !tile_ring[size_t(ty) * tx_n + end + 1].empty()) ++end;
      const auto key = std::make_pair(tx, end);
      if (const auto it = open.find(key); it != open.end()) {
        rects[it->second].ty1 = ty;
        next_open[key] = it->second;
      } else {
        rects.push_back({tx, end, ty, ty});
        next_open[key] = rects.size() - 1;
      }
      tx = end + 1;
    }
    open.swap(next_open);
  }
  size_t tiled_area = 0;
  for (const TileRect& t : rects)
    tiled_area += size_t(std::min(ww, (t.tx1 + 1) * kTile) - t.tx0 * kTile) *
                  size_t(std::min(wh, (t.ty1 + 1) * kTile) - t.ty0 * kTile);
  const bool by_tiles = o.tile_scoring && o.windows > 1 && 2 * tiled_area <= size_t(ww) * wh;
  // Squared (albedo, normal) difference of each ring pixel ring[k] (k in ks) whose window
  // coordinates are c[2 * i], c[2 * i + 1] with i = index(q), into e[k]; summed in ring order
  // afterwards, so both ways of scoring give the same bits.
  std::vector<double> e(ring.size());
  auto score = [&](const std::vector<int32_t>& c, const std::vector<size_t>& ks, auto&& index) {
    for (size_t k : ks) {
      const int q = ring[k];
      const size_t i = index(q);
      double err = 0;
      const int s = c[2 * i + 1] * ex.width + c[2 * i];
      const Vec3 n = normal_of(s, size_t(q));
      for (int ch = 0; ch < 3; ++ch) {
        const double da = ex.albedo[3 * size_t(s) + ch] - target.albedo[3 * size_t(q) + ch];
        const double dn = n[ch] - target.normal[3 * size_t(q) + ch];
        err += da * da + dn * dn;
      }
      e[k] = err;
    }
  };
  std::vector<size_t> all_ring(ring.size());
  for (size_t k = 0; k < ring.size(); ++k) all_ring[k] = k;
  double best = std::numeric_limits<double>::infinity();
  std::vector<int32_t> best_coords;
  for (int k = 0; k < o.windows; ++k) {
    const int64_t ox = offset(rng), oy = offset(rng);
    double err = 0;
    std::vector<int32_t> c;
    if (by_tiles) {
      for (const TileRect& t : rects) {
        const int x0t = t.tx0 * kTile, y0t = t.ty0 * kTile;
        const int tw = std::min(ww, (t.tx1 + 1) * kTile) - x0t, th = std::min(wh, (t.ty1 + 1) * kTile) - y0t;
        const std::vector<int32_t> ct = synthesizer.synthesise({ox + x0t, oy + y0t, tw, th}, p->options);
        for (int ty = t.ty0; ty <= t.ty1; ++ty)
          for (int tx = t.tx0; tx <= t.tx1; ++tx)
            score(ct, tile_ring[size_t(ty) * tx_n + tx],
                  [&](int q) { return size_t(q / W - wy0 - y0t) * tw + size_t(q % W - wx0 - x0t); });
      }
    } else {
      c = synthesizer.synthesise({ox, oy, ww, wh}, p->options);
      score(c, all_ring, [&](int q) { return size_t(q / W - wy0) * ww + size_t(q % W - wx0); });
    }
    for (double v : e) err += v;
    err /= double(std::max<size_t>(1, ring.size()));
    if (err < best) best = err, best_coords = std::move(c), r.window_x = ox, r.window_y = oy;
    if (o.progress) o.progress(double(k + 1) / (o.windows + (by_tiles ? 1 : 0)));
  }
  if (by_tiles) best_coords = synthesizer.synthesise({r.window_x, r.window_y, ww, wh}, p->options);
  r.ring_error = ring.empty() ? 0.0 : best;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x) {
      const size_t q = size_t(y) * W + x;
      if (!(mask[q] > 0)) continue;
      const size_t i = size_t(y - wy0) * ww + (x - wx0);
      const int s = best_coords[2 * i + 1] * ex.width + best_coords[2 * i];
      r.source[q] = s;
      std::copy_n(&ex.albedo[3 * size_t(s)], 3, &r.image.albedo[3 * q]);
      const Vec3 n = normal_of(s, q);
      std::copy(n.begin(), n.end(), &r.image.normal[3 * q]);
      ++r.visited;
    }
  if (o.xi >= 0) detail::saturate_synthesised(r.image, target, r.source, o.xi);
  return r;
}

}  // namespace proctex::rgbn
