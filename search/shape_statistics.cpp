// Orientation and elongation statistics of a texture's lightness (search/selection.h).
#include <algorithm>
#include <cmath>
#include <vector>

#include "image/image.h"
#include "search/selection.h"

namespace proctex::search {

namespace {

// A single-channel image; borders are clamped (a photo does not wrap around).
struct Plane {
  int w = 0, h = 0;
  std::vector<float> v;
  float at(int x, int y) const { return v[static_cast<size_t>(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)]; }
};

Plane blurred(const Plane& in, float sigma) {
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0f * sigma)));
  std::vector<float> k(2 * radius + 1);
  float total = 0;
  for (int i = -radius; i <= radius; ++i) total += k[i + radius] = std::exp(-0.5f * i * i / (sigma * sigma));
  for (float& x : k) x /= total;
  Plane tmp = in, out = in;
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      float s = 0;
      for (int i = -radius; i <= radius; ++i) s += k[i + radius] * in.at(x + i, y);
      tmp.v[static_cast<size_t>(y) * in.w + x] = s;
    }
  for (int y = 0; y < in.h; ++y)
    for (int x = 0; x < in.w; ++x) {
      float s = 0;
      for (int i = -radius; i <= radius; ++i) s += k[i + radius] * tmp.at(x, y + i);
      out.v[static_cast<size_t>(y) * in.w + x] = s;
    }
  return out;
}

Plane halved(const Plane& in) {
  Plane out{in.w / 2, in.h / 2, {}};
  out.v.resize(static_cast<size_t>(out.w) * out.h);
  for (int y = 0; y < out.h; ++y)
    for (int x = 0; x < out.w; ++x)
      out.v[static_cast<size_t>(y) * out.w + x] =
          0.25f * (in.at(2 * x, 2 * y) + in.at(2 * x + 1, 2 * y) + in.at(2 * x, 2 * y + 1) + in.at(2 * x + 1, 2 * y + 1));
  return out;
}

// The statistics of one pyramid level, appended to `out` (kShapeStatisticsPerLevel values).
void level_statistics(const Plane& level, std::vector<double>& out) {
  const Plane smooth = blurred(level, 1.0f);
  const int w = level.w, h = level.h;
  const size_t n = static_cast<size_t>(w) * h;
  Plane jxx{w, h, std::vector<float>(n)}, jxy = jxx, jyy = jxx;
  double gxx = 0, gxy = 0, gyy = 0;  // the whole level's gradient tensor
  double ridge_num = 0, ridge_den = 0, blob = 0, polarity = 0, polarity_den = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      const float c = smooth.at(x, y);
      const float gx = 0.5f * (smooth.at(x + 1, y) - smooth.at(x - 1, y));
      const float gy = 0.5f * (smooth.at(x, y + 1) - smooth.at(x, y - 1));
      jxx.v[i] = gx * gx;
      jxy.v[i] = gx * gy;
      jyy.v[i] = gy * gy;
      gxx += gx * gx;
      gxy += gx * gy;
      gyy += gy * gy;
      // Hessian: a ridge (blade, crack, vein) has one large curvature, a blob (pebble, cell) two of
      // one sign; the sign of the large one says bright or dark.
      const float hxx = smooth.at(x + 1, y) - 2 * c + smooth.at(x - 1, y);
      const float hyy = smooth.at(x, y + 1) - 2 * c + smooth.at(x, y - 1);
      const float hxy = 0.25f * (smooth.at(x + 1, y + 1) - smooth.at(x - 1, y + 1) - smooth.at(x + 1, y - 1) +
                                 smooth.at(x - 1, y - 1));
      const double m = 0.5 * (hxx + hyy), r = std::hypot(0.5 * (hxx - hyy), static_cast<double>(hxy));
      const double h1 = m + r, h2 = m - r;
      const double big = std::abs(h1) >= std::abs(h2) ? h1 : h2, small = std::abs(h1) >= std::abs(h2) ? h2 : h1;
      const double weight = std::abs(big) + std::abs(small);
      ridge_num += std::abs(big) - std::abs(small);
      ridge_den += weight;
      // a blob curves strongly both ways: counted by the smaller curvature (a straight ridge's
      // second curvature is ~0 with either sign)
      if (h1 * h2 > 0) blob += 2.0 * std::abs(small);
      // weighted by |big|: the sign of the strongest curvatures (a thin line's centre, not the
      // wider, weaker shoulders around it, whose sum cancels the centre's)
      polarity += big * std::abs(big);
      polarity_den += big * big;
    }
  auto ratio = [](double a, double b) { return b > 1e-20 ? a / b : 0.0; };
  // Coherence of the local structure tensor at a small and a wide integration scale: elongated
  // structures (blades, grain, stripes) stay coherent over the wide window, blobs and noise do not.
  for (float sigma : {1.5f, 4.0f}) {
    const Plane a = blurred(jxx, sigma), b = blurred(jxy, sigma), d = blurred(jyy, sigma);
    double coherent = 0, trace_total = 0, coherent_share = 0, cos4 = 0, sin4 = 0;
    for (size_t i = 0; i < n; ++i) {
      const double trace = a.v[i] + d.v[i];
      const double dx = a.v[i] - d.v[i], dy = 2.0 * b.v[i];
      const double diff = std::hypot(dx, dy);
      coherent += diff;
      trace_total += trace;
      if (diff > 0.6 * trace) coherent_share += trace;
      if (sigma < 2.0f && diff > 1e-20) {  // doubled orientation (dx, dy) / diff, squared again: 4 theta
        cos4 += (dx * dx - dy * dy) / diff;
        sin4 += 2.0 * dx * dy / diff;
      }
    }
    out.push_back(ratio(coherent, trace_total));
    out.push_back(ratio(coherent_share, trace_total));
    if (sigma < 2.0f) out.push_back(ratio(std::hypot(cos4, sin4), coherent));  // square grids: two directions
  }
  // One dominant direction over the whole level (stripes, grain, brushed metal, a lawn's blades).
  out.push_back(ratio(std::hypot(gxx - gyy, 2.0 * gxy), gxx + gyy));
  out.push_back(ratio(ridge_num, ridge_den));
  out.push_back(ratio(blob, ridge_den));
  out.push_back(ratio(polarity, polarity_den));
}

}  // namespace

std::vector<double> shape_statistics(const Image& view, int resolution) {
  const Image square = view.width == resolution && view.height == resolution
                           ? view
                           : resize(center_crop_square(view), resolution, resolution);
  Plane level{resolution, resolution, {}};
  level.v.resize(static_cast<size_t>(resolution) * resolution);
  for (size_t i = 0; i < level.v.size(); ++i) {
    // lightness (CIE L*/100) of the pixel: perceptual, so dark and bright structure weigh alike
    const double y = std::max(0.0f, luminance(square.pixels.data() + 3 * i));
    level.v[i] = static_cast<float>(y > 216.0 / 24389.0 ? 1.16 * std::cbrt(y) - 0.16 : y * 24389.0 / 2700.0);
  }
  std::vector<double> out;
  for (int l = 0; l < kShapeLevels; ++l) {
    level_statistics(level, out);
    if (l + 1 < kShapeLevels) level = halved(level);
  }
  return out;
}

}  // namespace proctex::search
