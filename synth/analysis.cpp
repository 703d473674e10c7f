#include "synth/analysis.h"
#include "synth/plane.h"
#include "synth/cache_io.h"
#include "metrics/fft.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <mutex>
#include <unistd.h>
#include <thread>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "core/error.h"
#include "core/parallel.h"
#include "core/hash.h"

namespace proctex::synth {
namespace {

using detail::level_count;
using detail::reflect;
using detail::Sampler;
using detail::wrap;

// Gaussian stack by repeated a-trous binomial filtering: level l = level l+1 filtered with
// [1 4 6 4 1] / 16 at spacing h_{l+1}, separably. Returns levels 0..L, each planar like `ch`.
std::vector<std::vector<float>> gaussian_stack(const Channels& ch, int L, const Sampler& s) {
  const int w = ch.width, h = ch.height;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<std::vector<float>> stack(L + 1);
  stack[L] = ch.data;
  const float k[5] = {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
  std::vector<float> tmp(ch.data.size());
  for (int l = L - 1; l >= 0; --l) {
    const int sp = 1 << (L - l - 1);
    const auto& src = stack[l + 1];
    auto& dst = stack[l];
    dst.assign(src.size(), 0.0f);
    for (int c = 0; c < ch.count; ++c) {
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
    // Filtered normals are shorter than 1: renormalise (compared on components, kept unit length).
    for (size_t g = 0; g < ch.normal_groups.size(); ++g) {
      const int c0 = ch.normal_groups[g];
      const float scale = ch.normal_scale[g];
      if (scale <= 0) continue;
      for (size_t i = 0; i < n; ++i) {
        float v[3];
        for (int j = 0; j < 3; ++j) v[j] = dst[(c0 + j) * n + i] / scale;
        const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (len < 1e-6f) {
          v[0] = 0, v[1] = 0, v[2] = 1;
        } else {
          for (float& e : v) e /= len;
        }
        for (int j = 0; j < 3; ++j) dst[(c0 + j) * n + i] = v[j] * scale;
      }
    }
  }
  return stack;
}

// Top `dims` principal directions of the rows of X (columns = variables), largest first.
Eigen::MatrixXd principal_axes(const Eigen::MatrixXd& X, int dims, Eigen::VectorXd& mean, double& top_variance) {
  mean = X.colwise().mean();
  const Eigen::MatrixXd centred = X.rowwise() - mean.transpose();
  const Eigen::MatrixXd cov = (centred.transpose() * centred) / std::max<double>(1.0, double(X.rows() - 1));
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(cov);
  const int D = static_cast<int>(cov.rows());
  Eigen::MatrixXd axes(D, dims);
  axes.setZero();
  for (int i = 0; i < std::min(dims, D); ++i) {
    Eigen::VectorXd v = es.eigenvectors().col(D - 1 - i);
    // Fix the sign (largest component positive) so the basis does not depend on the solver's whim.
    Eigen::Index arg;
    v.cwiseAbs().maxCoeff(&arg);
    if (v(arg) < 0) v = -v;
    axes.col(i) = v;
  }
  top_variance = std::max(0.0, es.eigenvalues()(D - 1));
  return axes;
}

// Rows used to estimate a covariance: every texel up to 8k, else a regular subsample (8k rows
// estimate a 75 x 75 covariance well; 16k cost 12% of a 256^2 analysis in the GEMM).
std::vector<size_t> sample_rows(size_t n) {
  const size_t target = 8192;
  std::vector<size_t> rows;
  const size_t step = std::max<size_t>(1, n / target);
  for (size_t i = 0; i < n; i += step) rows.push_back(i);
  return rows;
}

void appearance_level(const Channels& ch, const std::vector<float>& plane, int spacing, const Sampler& s,
                      AnalysisLevel& out) {
  const int w = ch.width, h = ch.height, C = ch.count;
  const size_t n = static_cast<size_t>(w) * h;
  const int D = 25 * C;
  // Gaussian weights over the 5x5 taps (sigma 1.5 taps): the centre matters most.
  float tapw[25];
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx) tapw[(dy + 2) * 5 + dx + 2] = std::sqrt(std::exp(-(dx * dx + dy * dy) / 4.5f));
  auto gather = [&](size_t i, double* row) {
    const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
    int k = 0;
    for (int dy = -2; dy <= 2; ++dy) {
      const int yy = s.iy(y + dy * spacing);
      for (int dx = -2; dx <= 2; ++dx) {
        const int xx = s.ix(x + dx * spacing);
        const size_t t = static_cast<size_t>(yy) * w + xx;
        const float wt = tapw[(dy + 2) * 5 + dx + 2];
        for (int c = 0; c < C; ++c) row[k++] = wt * plane[c * n + t];
      }
    }
  };
  const auto rows = sample_rows(n);
  Eigen::MatrixXd X(rows.size(), D);
  std::vector<double> buf(D);
  for (size_t r = 0; r < rows.size(); ++r) {
    gather(rows[r], buf.data());
    for (int d = 0; d < D; ++d) X(r, d) = buf[d];
  }
  Eigen::VectorXd mean;
  double top = 0;
  const Eigen::MatrixXd axes = principal_axes(X, kAppearanceDims, mean, top);
  const double scale = top > 1e-12 ? 127.0 / (3.5 * std::sqrt(top)) : 0.0;
  out.appearance.resize(n * kAppearanceDims);
  Eigen::VectorXd v(D);
  for (size_t i = 0; i < n; ++i) {
    gather(i, buf.data());
    for (int d = 0; d < D; ++d) v(d) = buf[d] - mean(d);
    for (int j = 0; j < kAppearanceDims; ++j) {
      const double p = std::clamp(std::round(axes.col(j).dot(v) * scale), -127.0, 127.0);
      out.appearance[i * kAppearanceDims + j] = static_cast<int8_t>(p);
    }
  }
}

const int kTapDx[kNeighbourTaps] = {0, -1, 1, -1, 1, 0, -1, 1, 0};
const int kTapDy[kNeighbourTaps] = {0, -1, -1, 1, 1, -1, 0, 0, 1};

void gather_taps(const AnalysisLevel& lv, int w, int h, bool toroidal, int x, int y, int8_t* taps) {
  for (int t = 0; t < kNeighbourTaps; ++t) {
    // Bounded exemplars mirror at the border: a synthesised patch that runs across the exemplar's
    // wrap (where synthesis coordinates wrap) then matches worse than one inside it, so
    // correction moves it away from the seam. With wrapped taps such patches matched perfectly
    // and were copied across the border about as often as inside (test BoundedExemplar...).
    const int xx = toroidal ? wrap(x + kTapDx[t] * lv.spacing, w) : reflect(x + kTapDx[t] * lv.spacing, w);
    const int yy = toroidal ? wrap(y + kTapDy[t] * lv.spacing, h) : reflect(y + kTapDy[t] * lv.spacing, h);
    std::memcpy(taps + t * kAppearanceDims, &lv.appearance[(static_cast<size_t>(yy) * w + xx) * kAppearanceDims],
                kAppearanceDims);
  }
}

void neighbourhood_level(int w, int h, bool toroidal, AnalysisLevel& lv) {
  const size_t n = static_cast<size_t>(w) * h;
  const auto rows = sample_rows(n);
  Eigen::MatrixXd X(rows.size(), kNeighbourDims);
  int8_t taps[kNeighbourDims];
  for (size_t r = 0; r < rows.size(); ++r) {
    gather_taps(lv, w, h, toroidal, static_cast<int>(rows[r] % w), static_cast<int>(rows[r] / w), taps);
    for (int d = 0; d < kNeighbourDims; ++d) X(r, d) = taps[d];
  }
  Eigen::VectorXd mean;
  double top = 0;
  const Eigen::MatrixXd axes = principal_axes(X, kAppearanceDims, mean, top);
  lv.projection.resize(kNeighbourDims * kAppearanceDims);
  for (int d = 0; d < kNeighbourDims; ++d)
    for (int j = 0; j < kAppearanceDims; ++j)
      lv.projection[d * kAppearanceDims + j] = static_cast<int32_t>(std::lround(axes(d, j) * (1 << kProjectionShift)));
  lv.neighbourhood.resize(n * kAppearanceDims);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      gather_taps(lv, w, h, toroidal, x, y, taps);
      const auto p = project_neighbourhood(lv, taps);
      std::memcpy(&lv.neighbourhood[(static_cast<size_t>(y) * w + x) * kAppearanceDims], p.data(), sizeof p);
    }
}

// A small deterministic generator (the same numbers on every platform, unlike std distributions).
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

// For every texel, the most similar texel (projected neighbourhood) at least `sep` texels away in
// either axis: PatchMatch (random init, propagation, shrinking random search).
// 3 PatchMatch iterations: each costs ~0.12 s CPU at 256^2 x 9 levels; more barely lowers the
// neighbourhood distances of the candidates.
constexpr int kIterations = 3;
// With `avoid` (the second candidates), the match must also be `sep` away from avoid[i]: the third
// candidate of k = 3.
std::vector<int32_t> coherence_level(int w, int h, bool toroidal, const AnalysisLevel& lv, uint64_t seed,
                                     const std::vector<int32_t>* avoid = nullptr) {
  const size_t n = static_cast<size_t>(w) * h;
  const int sep = std::max(2, static_cast<int>(std::lround(0.05 * std::max(w, h))));
  const int16_t* f = lv.neighbourhood.data();
  auto dist = [&](size_t a, size_t b) {
    int32_t d = 0;
    for (int j = 0; j < kAppearanceDims; ++j) {
      const int32_t e = int32_t(f[a * kAppearanceDims + j]) - f[b * kAppearanceDims + j];
      d += e * e;
    }
    return d;
  };
  auto far_enough = [&](int x0, int y0, int x1, int y1) {
    int dx = std::abs(x0 - x1), dy = std::abs(y0 - y1);
    if (toroidal) dx = std::min(dx, w - dx), dy = std::min(dy, h - dy);
    return std::max(dx, dy) >= sep;
  };
  auto admissible = [&](int x0, int y0, int x1, int y1) {
    if (!far_enough(x0, y0, x1, y1)) return false;
    if (!avoid) return true;
    const int a = (*avoid)[static_cast<size_t>(y0) * w + x0];
    return far_enough(a % w, a / w, x1, y1);
  };
  SplitMix rng{seed};
  std::vector<int32_t> nn(n);
  std::vector<int32_t> best(n);
  for (size_t i = 0; i < n; ++i) {
    const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
    int cx, cy;
    do {
      cx = rng.below(w), cy = rng.below(h);
    } while (!admissible(x, y, cx, cy));
    nn[i] = cy * w + cx;
    best[i] = dist(i, nn[i]);
  }
  auto consider = [&](size_t i, int x, int y, int cx, int cy) {
    cx = toroidal ? wrap(cx, w) : std::clamp(cx, 0, w - 1);
    cy = toroidal ? wrap(cy, h) : std::clamp(cy, 0, h - 1);
    if (!admissible(x, y, cx, cy)) return;
    const size_t c = static_cast<size_t>(cy) * w + cx;
    const int32_t d = dist(i, c);
    if (d < best[i] || (d == best[i] && static_cast<int32_t>(c) < nn[i])) best[i] = d, nn[i] = static_cast<int32_t>(c);
  };
  for (int it = 0; it < kIterations; ++it) {
    const bool fwd = it % 2 == 0;
    const int step = fwd ? 1 : -1;
    for (size_t k = 0; k < n; ++k) {
      const size_t i = fwd ? k : n - 1 - k;
      const int x = static_cast<int>(i % w), y = static_cast<int>(i / w);
      // Propagation: the neighbour's match shifted by one.
      const int px = x - step, py = y - step;
      if (toroidal || (px >= 0 && px < w)) {
        const int j = nn[static_cast<size_t>(y) * w + wrap(px, w)];
        consider(i, x, y, j % w + step, j / w);
      }
      if (toroidal || (py >= 0 && py < h)) {
        const int j = nn[static_cast<size_t>(wrap(py, h)) * w + x];
        consider(i, x, y, j % w, j / w + step);
      }
      // Random search around the current match, radius halving.
      for (int r = std::max(w, h) / 2; r >= 1; r /= 2) {
        const int bx = nn[i] % w, by = nn[i] / w;
        consider(i, x, y, bx + rng.below(2 * r + 1) - r, by + rng.below(2 * r + 1) - r);
      }
    }
  }
  return nn;
}

std::string content_hash(const Exemplar& ex, const Channels& ch, bool toroidal, int candidates) {
  std::string key = fmt::format("proctex-synth-analysis v{} {}x{} c{} t{} w{:.6f} k{}|", kAnalysisVersion, ch.width,
                                ch.height, ch.count, toroidal ? 1 : 0, ex.map_weight, candidates);
  for (int g : ch.normal_groups) key += fmt::format("n{};", g);
  key.append(reinterpret_cast<const char*>(ch.data.data()), ch.data.size() * sizeof(float));
  return fnv1a_hex(key);
}

constexpr uint32_t kMagic = 0x53594e54;  // "SYNT"

using detail::read_vec;
using detail::write_vec;

bool load_cache(const std::filesystem::path& file, Analysis& a) {
  std::ifstream f(file, std::ios::binary);
  if (!f) return false;
  uint32_t magic = 0, version = 0;
  int32_t hdr[5];
  f.read(reinterpret_cast<char*>(&magic), 4);
  f.read(reinterpret_cast<char*>(&version), 4);
  f.read(reinterpret_cast<char*>(hdr), sizeof hdr);
  if (!f || magic != kMagic || version != kAnalysisVersion) return false;
  if (hdr[0] != a.width || hdr[1] != a.height || hdr[2] != a.levels || hdr[3] != (a.toroidal ? 1 : 0) ||
      hdr[4] != a.candidates)
    return false;
  const uint64_t n = static_cast<uint64_t>(a.width) * a.height;
  a.level.resize(a.levels + 1);
  for (int l = 0; l <= a.levels; ++l) {
    auto& lv = a.level[l];
    lv.spacing = 1 << (a.levels - l);
    if (!read_vec(f, lv.appearance, n * kAppearanceDims) || !read_vec(f, lv.neighbourhood, n * kAppearanceDims) ||
        !read_vec(f, lv.coherent, n) || !read_vec(f, lv.projection, uint64_t(kNeighbourDims) * kAppearanceDims))
      return false;
    if (!read_vec(f, lv.coherent2, a.candidates >= 3 ? n : 0)) return false;
    for (int32_t c : lv.coherent)
      if (c < 0 || static_cast<uint64_t>(c) >= n) return false;
    for (int32_t c : lv.coherent2)
      if (c < 0 || static_cast<uint64_t>(c) >= n) return false;
  }
  char extra;
  return !f.read(&extra, 1);  // exactly at the end
}

void save_cache(const std::filesystem::path& file, const Analysis& a) {
  std::error_code ec;
  std::filesystem::create_directories(file.parent_path(), ec);
  const auto tmp = file.string() + fmt::format(".tmp{}", static_cast<long>(::getpid()));
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return;  // the cache is an optimisation: an unwritable folder is not an error
    const uint32_t magic = kMagic, version = kAnalysisVersion;
    const int32_t hdr[5] = {a.width, a.height, a.levels, a.toroidal ? 1 : 0, a.candidates};
    f.write(reinterpret_cast<const char*>(&magic), 4);
    f.write(reinterpret_cast<const char*>(&version), 4);
    f.write(reinterpret_cast<const char*>(hdr), sizeof hdr);
    for (const auto& lv : a.level) {
      write_vec(f, lv.appearance);
      write_vec(f, lv.neighbourhood);
      write_vec(f, lv.coherent);
      write_vec(f, lv.projection);
      write_vec(f, lv.coherent2);
    }
    if (!f) {
      f.close();
      std::filesystem::remove(tmp, ec);
      return;
    }
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) std::filesystem::remove(tmp, ec);
}

// The most self-similar translations (Analysis::shifts): the autocorrelation of the mean-free
// channels by FFT (Wiener-Khinchin), its local maxima away from 0, best first.
std::vector<int32_t> self_similar_shifts(const Channels& ch, std::vector<float>& correlation) {
  namespace fd = metrics::detail;
  const int w = ch.width, h = ch.height, hw = w / 2 + 1;
  const size_t n = static_cast<size_t>(w) * h;
  std::vector<double> acf(n, 0.0);
  fd::FftwArray<float> in(n), back(n);
  fd::FftwArray<fd::Complex> spec(static_cast<size_t>(h) * hw);
  for (int c = 0; c < ch.count; ++c) {
    const float* plane = ch.data.data() + c * n;
    double mean = 0;
    for (size_t i = 0; i < n; ++i) mean += plane[i];
    mean /= n;
    for (size_t i = 0; i < n; ++i) in[i] = static_cast<float>(plane[i] - mean);
    fd::fft_r2c(h, w, in, spec);
    for (size_t i = 0; i < spec.size(); ++i) spec[i] = fd::Complex(std::norm(spec[i]), 0.0f);
    fd::fft_c2r(h, w, spec, back);
    for (size_t i = 0; i < n; ++i) acf[i] += back[i];
  }
  std::vector<std::pair<double, int>> peaks;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int dx = x <= w / 2 ? x : x - w, dy = y <= h / 2 ? y : y - h;
      if (8 * std::abs(dx) < w && 8 * std::abs(dy) < h) continue;  // too close to no shift at all
      const double v = acf[static_cast<size_t>(y) * w + x];
      bool peak = true;
      for (int ey = -1; ey <= 1 && peak; ++ey)
        for (int ex = -1; ex <= 1; ++ex) {
          if ((ex || ey) && acf[static_cast<size_t>(detail::wrap(y + ey, h)) * w + detail::wrap(x + ex, w)] > v) {
            peak = false;
            break;
          }
        }
      if (peak) peaks.emplace_back(-v, y * w + x);  // ties: the lower index first (deterministic)
    }
  std::sort(peaks.begin(), peaks.end());
  std::vector<int32_t> out;
  correlation.clear();
  for (size_t k = 0; k < peaks.size() && out.size() < 2 * static_cast<size_t>(kMaxShifts); ++k) {
    const int x = peaks[k].second % w, y = peaks[k].second / w;
    correlation.push_back(acf[0] > 0 ? static_cast<float>(-peaks[k].first / acf[0]) : 0.0f);
    out.push_back(x <= w / 2 ? x : x - w);
    out.push_back(y <= h / 2 ? y : y - h);
  }
  return out;
}

void fill_texels(const Channels& ch, Analysis& a) {
  a.shifts = self_similar_shifts(ch, a.shift_correlation);
  const size_t n = static_cast<size_t>(ch.width) * ch.height;
  a.texel_channels = ch.count;
  a.texels.resize(n * ch.count);
  for (int c = 0; c < ch.count; ++c)
    for (size_t i = 0; i < n; ++i)
      a.texels[i * ch.count + c] = static_cast<int16_t>(std::lround(std::clamp(ch.data[c * n + i], -64.0f, 64.0f) * 255.0f));
}

int candidates_of(const AnalysisOptions& o) {
  if (o.candidates != 2 && o.candidates != 3)
    throw UsageError(fmt::format("{} k-coherence candidates", o.candidates), "2 (default) or 3");
  return o.candidates;
}

bool resolve_toroidal(const Exemplar& ex, const AnalysisOptions& o) {
  if (o.tiling == Tiling::Toroidal) return true;
  if (o.tiling == Tiling::Bounded) return false;
  return tiles_seamlessly(ex);
}

}  // namespace

std::array<int16_t, kAppearanceDims> project_neighbourhood(const AnalysisLevel& lv, const int8_t* taps) {
  std::array<int16_t, kAppearanceDims> out{};
  int32_t acc[kAppearanceDims] = {};
  const int32_t* p = lv.projection.data();
  for (int d = 0; d < kNeighbourDims; ++d, p += kAppearanceDims) {  // rows in order: vectorises
    const int32_t t = taps[d];
    for (int j = 0; j < kAppearanceDims; ++j) acc[j] += t * p[j];
  }
  for (int j = 0; j < kAppearanceDims; ++j) out[j] = static_cast<int16_t>(acc[j] >> kProjectionShift);
  return out;
}

bool tiles_seamlessly(const Exemplar& ex) {
  const Image& im = ex.colour;
  const int w = im.width, h = im.height;
  std::vector<float> v(static_cast<size_t>(w) * h * 3);
  for (size_t i = 0; i < v.size(); ++i) v[i] = linear_to_srgb(std::clamp(im.pixels[i], 0.f, 1.f));
  auto diff = [&](int x0, int y0, int x1, int y1) {
    double d = 0;
    for (int c = 0; c < 3; ++c) {
      const double e = v[(static_cast<size_t>(y0) * w + x0) * 3 + c] - v[(static_cast<size_t>(y1) * w + x1) * 3 + c];
      d += e * e;
    }
    return d;
  };
  // The mean step between every pair of adjacent rows (and columns), the wrap pair included: the
  // exemplar tiles when the wrap's step is no larger than the 95th percentile of the inner ones.
  // (A mean over all pixels was too strict: a tiling brick texture whose border runs along a mortar
  // line has a sharp but natural step there.)
  auto seam_is_natural = [&](bool rows) {
    const int n = rows ? h : w, len = rows ? w : h;
    std::vector<double> steps;
    for (int k = 0; k + 1 < n; ++k) {
      double s = 0;
      for (int t = 0; t < len; ++t) s += rows ? diff(t, k, t, k + 1) : diff(k, t, k + 1, t);
      steps.push_back(s / len);
    }
    double seam = 0;
    for (int t = 0; t < len; ++t) seam += rows ? diff(t, n - 1, t, 0) : diff(n - 1, t, 0, t);
    seam /= len;
    std::sort(steps.begin(), steps.end());
    const double q95 = steps[std::min(steps.size() - 1, static_cast<size_t>(0.95 * steps.size()))];
    return seam <= 1.1 * q95 + 1e-12;
  };
  return seam_is_natural(true) && seam_is_natural(false);
}

Analysis analyse(const Exemplar& ex, const AnalysisOptions& options) {
  validate(ex);
  const auto start = std::chrono::steady_clock::now();
  const Channels ch = matching_channels(ex);
  Analysis a;
  a.width = ch.width;
  a.height = ch.height;
  a.levels = level_count(ch.width, ch.height);
  a.toroidal = resolve_toroidal(ex, options);
  a.candidates = candidates_of(options);
  a.hash = content_hash(ex, ch, a.toroidal, a.candidates);
  fill_texels(ch, a);
  const Sampler s{ch.width, ch.height, a.toroidal};
  const auto stack = gaussian_stack(ch, a.levels, s);
  a.level.resize(a.levels + 1);
  parallel_for(a.levels + 1, 0, [&](int l) {
    auto& lv = a.level[l];
    lv.spacing = 1 << (a.levels - l);
    appearance_level(ch, stack[l], lv.spacing, s, lv);
    neighbourhood_level(ch.width, ch.height, a.toroidal, lv);
    lv.coherent = coherence_level(ch.width, ch.height, a.toroidal, lv, 0x5eed0000u + static_cast<uint64_t>(l));
    if (a.candidates >= 3)
      lv.coherent2 = coherence_level(ch.width, ch.height, a.toroidal, lv, 0x5eed1000u + static_cast<uint64_t>(l),
                                     &lv.coherent);
  });
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return a;
}

std::filesystem::path default_cache_dir() {
  if (const char* d = std::getenv("PROCTEX_CACHE_DIR"); d && *d) return std::filesystem::path(d) / "synth";
  if (const char* d = std::getenv("XDG_CACHE_HOME"); d && *d) return std::filesystem::path(d) / "proctex" / "synth";
  if (const char* d = std::getenv("HOME"); d && *d) return std::filesystem::path(d) / ".cache" / "proctex" / "synth";
  return {};
}

Analysis analyse_cached(const Exemplar& ex, const AnalysisOptions& options, const std::filesystem::path& cache_dir) {
  if (cache_dir.empty()) return analyse(ex, options);
  validate(ex);
  const Channels ch = matching_channels(ex);
  Analysis a;
  a.width = ch.width;
  a.height = ch.height;
  a.levels = level_count(ch.width, ch.height);
  a.toroidal = resolve_toroidal(ex, options);
  a.candidates = candidates_of(options);
  a.hash = content_hash(ex, ch, a.toroidal, a.candidates);
  const auto file = cache_dir / (a.hash + ".bin");
  if (load_cache(file, a)) {
    fill_texels(ch, a);
    a.from_cache = true;
    return a;
  }
  Analysis fresh = analyse(ex, options);
  save_cache(file, fresh);
  return fresh;
}

}  // namespace proctex::synth
