#include "rgbn/filter.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "core/error.h"
#include "rgbn/parallel.h"

namespace proctex::rgbn {

FilterKind parse_filter_kind(const std::string& name) {
  if (name == "smooth") return FilterKind::Smooth;
  if (name == "sharpen") return FilterKind::Sharpen;
  if (name == "edge") return FilterKind::Edge;
  if (name == "detail") return FilterKind::Detail;
  if (name == "scale") return FilterKind::Scale;
  throw UsageError("unknown filter '" + name + "'", "use smooth, sharpen, edge, detail or scale");
}

std::string filter_kind_name(FilterKind kind) {
  switch (kind) {
    case FilterKind::Smooth: return "smooth";
    case FilterKind::Sharpen: return "sharpen";
    case FilterKind::Edge: return "edge";
    case FilterKind::Detail: return "detail";
    case FilterKind::Scale: return "scale";
  }
  return "?";
}

namespace {

std::vector<float> gaussian_taps(float sigma) {
  const int r = std::max(1, int(std::ceil(3.0f * sigma)));
  std::vector<float> taps(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += taps[i + r] = float(std::exp(-0.5 * double(i) * i / (double(sigma) * sigma)));
  for (float& t : taps) t = float(t / sum);
  return taps;
}

// exp(x) for x <= 0 as (1 + x/1024)^1024 (ten squarings): relative error ~x^2/2048 (0.4% at
// x = -3, where the weight is already 0.05), exactly 1 at 0, pure arithmetic so the bilateral's
// tap loop vectorises. Bit-trick versions (2^i via the exponent field) did not vectorise with
// GCC 12 at SSE2.
inline float fast_exp(float x) {
  float y = 1.0f + x * (1.0f / 1024.0f);
  y = 0.5f * (y + std::fabs(y));  // max(y, 0) without a branch
  y *= y, y *= y, y *= y, y *= y, y *= y;
  y *= y, y *= y, y *= y, y *= y, y *= y;
  return y;
}

// One tap (i, j) of the bilateral filter for a row of n output pixels: planar source rows s[6],
// centre rows c[6]; accumulates the weight and the weighted channels into acc (7 rows of n).
// On x86-64 an AVX2 clone is chosen at load time where the CPU has it (8 lanes instead of SSE2's
// 4; no FMA, so both clones give the same bits).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void bilateral_taps(const float* const* s, const float* const* c, float k, float ic, float in, int n, float* acc) {
  const float* __restrict s0 = s[0];
  const float* __restrict s1 = s[1];
  const float* __restrict s2 = s[2];
  const float* __restrict s3 = s[3];
  const float* __restrict s4 = s[4];
  const float* __restrict s5 = s[5];
  const float* __restrict q0 = c[0];
  const float* __restrict q1 = c[1];
  const float* __restrict q2 = c[2];
  const float* __restrict q3 = c[3];
  const float* __restrict q4 = c[4];
  const float* __restrict q5 = c[5];
  float* __restrict ww = acc;
  float* __restrict a0 = acc + n;
  float* __restrict a1 = acc + 2 * n;
  float* __restrict a2 = acc + 3 * n;
  float* __restrict n0 = acc + 4 * n;
  float* __restrict n1 = acc + 5 * n;
  float* __restrict n2 = acc + 6 * n;
#pragma omp simd
  for (int x = 0; x < n; ++x) {
    const float d0 = s0[x] - q0[x], d1 = s1[x] - q1[x], d2 = s2[x] - q2[x];
    const float e0 = s3[x] - q3[x], e1 = s4[x] - q4[x], e2 = s5[x] - q5[x];
    const float wt = k * fast_exp(ic * (d0 * d0 + d1 * d1 + d2 * d2) + in * (e0 * e0 + e1 * e1 + e2 * e2));
    ww[x] += wt;
    a0[x] += wt * s0[x], a1[x] += wt * s1[x], a2[x] += wt * s2[x];
    n0[x] += wt * s3[x], n1[x] += wt * s4[x], n2[x] += wt * s5[x];
  }
}

inline int border(int i, int n, bool wrap) {
  if (wrap) return ((i % n) + n) % n;
  return std::clamp(i, 0, n - 1);
}

void check_mask(const Rgbn& image, const Mask* mask) {
  if (mask && mask->size() != image.size())
    throw Error("the brush mask is not the size of the image", "give a mask of the same width and height");
}

}  // namespace

void gaussian_blur(std::vector<float>& f, int w, int h, float sigma, bool wrap) {
  if (!(sigma > 0)) return;
  const std::vector<float> taps = gaussian_taps(sigma);
  const int r = int(taps.size() / 2);
  std::vector<float> tmp(f.size());
  // Horizontal pass into tmp.
  detail::parallel_rows(h, [&](int y0, int y1) {
    std::vector<float> row(w + 2 * r);
    for (int y = y0; y < y1; ++y) {
      const float* src = &f[size_t(y) * w];
      for (int i = -r; i < w + r; ++i) row[i + r] = src[border(i, w, wrap)];
      float* dst = &tmp[size_t(y) * w];
      for (int x = 0; x < w; ++x) {
        float s = 0;
        const float* in = &row[x];
        for (int k = 0; k <= 2 * r; ++k) s += taps[k] * in[k];
        dst[x] = s;
      }
    }
  });
  // Vertical pass back into f, accumulating whole rows (cache friendly).
  detail::parallel_rows(h, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y) {
      float* dst = &f[size_t(y) * w];
      std::fill(dst, dst + w, 0.0f);
      for (int k = -r; k <= r; ++k) {
        const float t = taps[k + r];
        const float* src = &tmp[size_t(border(y + k, h, wrap)) * w];
        for (int x = 0; x < w; ++x) dst[x] += t * src[x];
      }
    }
  });
}

void apply_mask(const Rgbn& original, Rgbn& out, const Mask& mask) {
  for (size_t i = 0; i < original.size(); ++i) {
    const float m = std::clamp(mask[i], 0.0f, 1.0f);
    if (m >= 1.0f) continue;
    float* n = &out.normal[3 * i];
    const float* o = &original.normal[3 * i];
    float* a = &out.albedo[3 * i];
    const float* oa = &original.albedo[3 * i];
    if (m <= 0.0f) {
      std::copy(o, o + 3, n);
      std::copy(oa, oa + 3, a);
      continue;
    }
    for (int c = 0; c < 3; ++c) {
      n[c] = o[c] + m * (n[c] - o[c]);
      a[c] = oa[c] + m * (a[c] - oa[c]);
    }
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len > 1e-12f) {
      n[0] /= len, n[1] /= len, n[2] /= len;
    } else {
      std::copy(o, o + 3, n);
    }
  }
}

Rgbn filter(const Rgbn& image, const FilterOptions& o, const Mask* mask) {
  check_mask(image, mask);
  if (o.kind != FilterKind::Scale && !(o.sigma > 0 && o.sigma < 1000))
    throw UsageError("--sigma must be in (0, 1000) pixels", "e.g. --sigma 2");
  if ((o.kind == FilterKind::Edge || o.kind == FilterKind::Detail) && !(o.sigma2 > o.sigma))
    throw UsageError("--sigma2 must be larger than --sigma for edge and detail", "e.g. --sigma 1 --sigma2 4");
  if (!std::isfinite(o.amount)) throw UsageError("--amount must be finite", "e.g. --amount 1.5");
  const int w = image.width, h = image.height;
  std::vector<float> p, q;
  slopes(image, p, q);
  auto band = [&](std::vector<float>& f) {  // f <- response applied to f
    switch (o.kind) {
      case FilterKind::Smooth:
        gaussian_blur(f, w, h, o.sigma, o.wrap);
        break;
      case FilterKind::Sharpen: {
        std::vector<float> g = f;
        gaussian_blur(g, w, h, o.sigma, o.wrap);
        for (size_t i = 0; i < f.size(); ++i) f[i] += o.amount * (f[i] - g[i]);
        break;
      }
      case FilterKind::Edge:
      case FilterKind::Detail: {
        std::vector<float> g1 = f, g2 = f;
        gaussian_blur(g1, w, h, o.sigma, o.wrap);
        gaussian_blur(g2, w, h, o.sigma2, o.wrap);
        if (o.kind == FilterKind::Edge)
          for (size_t i = 0; i < f.size(); ++i) f[i] += o.amount * (g1[i] - g2[i]);
        else
          for (size_t i = 0; i < f.size(); ++i) f[i] = g1[i] - g2[i];
        break;
      }
      case FilterKind::Scale:
        for (float& v : f) v *= o.amount;
        break;
    }
  };
  band(p);
  band(q);
  Rgbn out = image;
  set_slopes(out, p, q);
  if (o.albedo && o.kind != FilterKind::Scale && o.kind != FilterKind::Detail) {
    std::vector<float> ch(image.size());
    for (int c = 0; c < 3; ++c) {
      for (size_t i = 0; i < ch.size(); ++i) ch[i] = image.albedo[3 * i + c];
      band(ch);
      for (size_t i = 0; i < ch.size(); ++i) out.albedo[3 * i + c] = std::max(0.0f, ch[i]);
    }
  }
  if (mask) apply_mask(image, out, *mask);
  return out;
}

Rgbn convolve(const Rgbn& image, const std::vector<float>& kernel, int kw, int kh, bool wrap, const Mask* mask) {
  check_mask(image, mask);
  if (kw % 2 == 0 || kh % 2 == 0 || kernel.size() != size_t(kw) * kh)
    throw UsageError("a kernel needs odd width and height and kw*kh values", "e.g. a 3x3 kernel of 9 values");
  const int w = image.width, h = image.height, rx = kw / 2, ry = kh / 2;
  std::vector<float> p, q, po(image.size()), qo(image.size());
  slopes(image, p, q);
  detail::parallel_rows(h, [&](int y0, int y1) {
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < w; ++x) {
        double sp = 0, sq = 0;
        for (int j = -ry; j <= ry; ++j)
          for (int i = -rx; i <= rx; ++i) {
            const size_t s = size_t(border(y - j, h, wrap)) * w + border(x - i, w, wrap);
            const float k = kernel[size_t(j + ry) * kw + (i + rx)];
            sp += k * p[s];
            sq += k * q[s];
          }
        po[size_t(y) * w + x] = float(sp);
        qo[size_t(y) * w + x] = float(sq);
      }
  });
  Rgbn out = image;
  set_slopes(out, po, qo);
  if (mask) apply_mask(image, out, *mask);
  return out;
}

Rgbn bilateral(const Rgbn& image, const BilateralOptions& o, const Mask* mask) {
  check_mask(image, mask);
  if (!(o.sigma_s > 0 && o.sigma_s < 100) || !(o.sigma_c > 0) || !(o.sigma_n > 0))
    throw UsageError("bilateral widths must be positive (sigma_s < 100)", "e.g. --sigma 2 --sigma-c 0.1 --sigma-n 0.2");
  const int w = image.width, h = image.height;
  // Taps on the disc of radius r = ceil(2 sigma_s) (spatial weight >= exp(-2) at its rim when
  // sigma_s is a whole number); the square's corners beyond it weigh less and would cost 65% more
  // taps at sigma_s = 2 (81 instead of 49).
  const int r = std::max(1, int(std::ceil(2.0f * o.sigma_s)));
  const int W = w + 2 * r, H = h + 2 * r;
  // Six planar channels (albedo, normal) padded by r clamped pixels: the tap loop then runs over
  // contiguous rows with no border tests, one SIMD lane per output pixel.
  std::vector<float> planes(size_t(6) * W * H);
  auto plane = [&](int c) { return planes.data() + size_t(c) * W * H; };
  for (int y = 0; y < H; ++y) {
    const int sy = std::clamp(y - r, 0, h - 1);
    for (int x = 0; x < W; ++x) {
      const int sx = std::clamp(x - r, 0, w - 1);
      const size_t si = size_t(sy) * w + sx, di = size_t(y) * W + x;
      for (int c = 0; c < 3; ++c) {
        plane(c)[di] = image.albedo[3 * si + c];
        plane(3 + c)[di] = image.normal[3 * si + c];
      }
    }
  }
  const float ic = -0.5f / (o.sigma_c * o.sigma_c), in = -0.5f / (o.sigma_n * o.sigma_n);
  Rgbn out = image;
  detail::parallel_rows(h, [&](int y0, int y1) {
    std::vector<float> acc(size_t(7) * w);
    float* aw = acc.data();
    for (int y = y0; y < y1; ++y) {
      std::fill(acc.begin(), acc.end(), 0.0f);
      const float* c0[6];
      for (int c = 0; c < 6; ++c) c0[c] = plane(c) + size_t(y + r) * W + r;
      for (int j = -r; j <= r; ++j)
        for (int i = -r; i <= r; ++i) {
          if (i * i + j * j > r * r) continue;
          const float k = std::exp(-0.5f * float(i * i + j * j) / (o.sigma_s * o.sigma_s));
          const float* s[6];
          for (int c = 0; c < 6; ++c) s[c] = plane(c) + size_t(y + r + j) * W + r + i;
          bilateral_taps(s, c0, k, ic, in, w, aw);
        }
      for (int x = 0; x < w; ++x) {
        float* on = out.n(x, y);
        const float sn[3] = {aw[4 * w + x], aw[5 * w + x], aw[6 * w + x]};
        const float len = std::sqrt(sn[0] * sn[0] + sn[1] * sn[1] + sn[2] * sn[2]);
        if (len > 1e-12f)
          for (int c = 0; c < 3; ++c) on[c] = sn[c] / len;
        if (o.albedo)
          for (int c = 0; c < 3; ++c) out.a(x, y)[c] = aw[(1 + c) * w + x] / aw[x];
      }
    }
  });
  if (mask) apply_mask(image, out, *mask);
  return out;
}

Mask disc_mask(int w, int h, float cx, float cy, float radius, float feather) {
  Mask m(size_t(w) * h, 0.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float d = std::hypot(x - cx, y - cy);
      float v = d <= radius ? 1.0f : 0.0f;
      if (feather > 0 && d > radius - feather && d <= radius) {
        const float t = (radius - d) / feather;  // 0 at the rim, 1 inside
        v = t * t * (3 - 2 * t);
      }
      m[size_t(y) * w + x] = v;
    }
  return m;
}

Mask rect_mask(int w, int h, int x0, int y0, int rw, int rh) {
  Mask m(size_t(w) * h, 0.0f);
  for (int y = std::max(0, y0); y < std::min(h, y0 + rh); ++y)
    for (int x = std::max(0, x0); x < std::min(w, x0 + rw); ++x) m[size_t(y) * w + x] = 1.0f;
  return m;
}

Mask image_mask(const Image& image, int w, int h) {
  if (image.width != w || image.height != h)
    throw Error("the mask image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                    ", the RGBN " + std::to_string(w) + "x" + std::to_string(h),
                "give a mask of the same size");
  Mask m = luminance(image);
  for (float& v : m) v = std::clamp(v, 0.0f, 1.0f);
  return m;
}

}  // namespace proctex::rgbn
