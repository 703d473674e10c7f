#include "metrics/detail.h"

#include <algorithm>

namespace proctex::metrics::detail {

namespace {
inline int mirror(int i, int n) {
  if (i < 0) i = -i;
  if (i >= n) i = 2 * n - 2 - i;
  return std::clamp(i, 0, n - 1);
}
}  // namespace

Plane blur5(const Plane& in) {
  const int n = in.size;
  Plane tmp{n, std::vector<float>(in.v.size())};
  Plane out{n, std::vector<float>(in.v.size())};
  constexpr float k0 = 6.0f / 16, k1 = 4.0f / 16, k2 = 1.0f / 16;
  for (int y = 0; y < n; ++y) {
    const float* row = in.v.data() + static_cast<std::size_t>(y) * n;
    float* o = tmp.v.data() + static_cast<std::size_t>(y) * n;
    // Mirrored borders (two pixels each side) apart; the interior loop vectorises.
    for (int x : {0, 1, n - 2, n - 1}) {
      o[x] = k0 * row[x] + k1 * (row[mirror(x - 1, n)] + row[mirror(x + 1, n)]) +
             k2 * (row[mirror(x - 2, n)] + row[mirror(x + 2, n)]);
    }
#pragma omp simd
    for (int x = 2; x < n - 2; ++x)
      o[x] = k0 * row[x] + k1 * (row[x - 1] + row[x + 1]) + k2 * (row[x - 2] + row[x + 2]);
  }
  for (int y = 0; y < n; ++y) {
    const float* r0 = tmp.v.data() + static_cast<std::size_t>(y) * n;
    const float* rm1 = tmp.v.data() + static_cast<std::size_t>(mirror(y - 1, n)) * n;
    const float* rp1 = tmp.v.data() + static_cast<std::size_t>(mirror(y + 1, n)) * n;
    const float* rm2 = tmp.v.data() + static_cast<std::size_t>(mirror(y - 2, n)) * n;
    const float* rp2 = tmp.v.data() + static_cast<std::size_t>(mirror(y + 2, n)) * n;
    float* o = out.v.data() + static_cast<std::size_t>(y) * n;
    for (int x = 0; x < n; ++x) o[x] = k0 * r0[x] + k1 * (rm1[x] + rp1[x]) + k2 * (rm2[x] + rp2[x]);
  }
  return out;
}

Plane decimate(const Plane& in) {
  const int m = in.size / 2;
  Plane out{m, std::vector<float>(static_cast<std::size_t>(m) * m)};
  for (int y = 0; y < m; ++y)
    for (int x = 0; x < m; ++x) out.at(x, y) = in.at(2 * x, 2 * y);
  return out;
}

double mean(std::span<const float> x) {
  double s = 0;
  for (float v : x) s += v;
  return x.empty() ? 0.0 : s / static_cast<double>(x.size());
}

double correlation(std::span<const float> a, std::span<const float> b) {
  const double ma = mean(a), mb = mean(b);
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    double da = a[i] - ma, db = b[i] - mb;
    sab += da * db;
    saa += da * da;
    sbb += db * db;
  }
  if (saa <= 1e-20 || sbb <= 1e-20) return 0.0;
  return sab / std::sqrt(saa * sbb);
}

float dot(const float* a, const float* b, std::size_t n) {
  float s = 0;
#pragma omp simd reduction(+ : s)
  for (std::size_t i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}

namespace {
constexpr std::size_t kChunk = 256;  // float partial sums over at most this many values
}

double sum(std::span<const float> x) {
  double total = 0;
  for (std::size_t i = 0; i < x.size(); i += kChunk) {
    const std::size_t m = std::min(kChunk, x.size() - i);
    const float* p = x.data() + i;
    float s = 0;
#pragma omp simd reduction(+ : s)
    for (std::size_t k = 0; k < m; ++k) s += p[k];
    total += s;
  }
  return total;
}

double centre(std::span<float> x) {
  if (x.empty()) return 0.0;
  const float m = static_cast<float>(sum(x) / static_cast<double>(x.size()));
  double ss = 0;
  for (std::size_t i = 0; i < x.size(); i += kChunk) {
    const std::size_t len = std::min(kChunk, x.size() - i);
    float* p = x.data() + i;
    float s = 0;
#pragma omp simd reduction(+ : s)
    for (std::size_t k = 0; k < len; ++k) {
      p[k] -= m;
      s += p[k] * p[k];
    }
    ss += s;
  }
  return ss;
}

double autocorrelation(const Plane& p, int dx, int dy, double energy) {
  const int n = p.size;
  dx = ((dx % n) + n) % n;
  double s = 0;
  for (int y = 0; y < n; ++y) {
    const float* r = p.v.data() + static_cast<std::size_t>(y) * n;
    const float* q = p.v.data() + static_cast<std::size_t>(((y + dy) % n + n) % n) * n;
    // Two runs without a modulo in the loop: x + dx < n, then the wrapped part.
    s += dot(r, q + dx, n - dx) + dot(r + (n - dx), q, dx);
  }
  return energy <= 1e-20 ? 0.0 : s / energy;
}

double autocorrelation(const Plane& p, int dx, int dy) {
  double energy = 0;
  for (int y = 0; y < p.size; ++y) {
    const float* r = p.v.data() + static_cast<std::size_t>(y) * p.size;
    energy += dot(r, r, p.size);
  }
  return autocorrelation(p, dx, dy, energy);
}

double weighted_rms(std::span<const float> a, std::span<const float> b,
                    std::span<const double> w) {
  double s = 0, sw = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    double d = static_cast<double>(a[i]) - b[i];
    s += w[i] * d * d;
    sw += w[i];
  }
  return sw > 0 ? std::sqrt(s / sw) : 0.0;
}

}  // namespace proctex::metrics::detail
