#include "rgbn/view.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "rgbn/parallel.h"

namespace proctex::rgbn {

Vec3 light_direction(float az, float el) {
  const float a = az * float(M_PI) / 180.0f, e = el * float(M_PI) / 180.0f;
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

Vec3 parse_light(const std::string& text) {
  std::vector<float> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stof(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw UsageError("cannot read light '" + text + "'", "give azimuth,elevation in degrees (135,45) or x,y,z");
    }
  }
  Vec3 l;
  if (v.size() == 2) {
    l = light_direction(v[0], v[1]);
  } else if (v.size() == 3) {
    const float len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(len > 1e-6f) || !std::isfinite(len))
      throw UsageError("light direction '" + text + "' has zero or non-finite length", "give a non-zero x,y,z");
    l = {v[0] / len, v[1] / len, v[2] / len};
  } else {
    throw UsageError("cannot read light '" + text + "'", "give azimuth,elevation in degrees (135,45) or x,y,z");
  }
  return l;
}

Image shade(const Rgbn& image, const ShadeOptions& o) {
  Image out(image.width, image.height);
  const Vec3 l = o.light;
  Vec3 hv = {l[0], l[1], l[2] + 1.0f};
  const float hl = std::sqrt(hv[0] * hv[0] + hv[1] * hv[1] + hv[2] * hv[2]);
  for (float& c : hv) c /= std::max(hl, 1e-12f);
  detail::parallel_rows(image.height, [&](int y0, int y1) {
    for (size_t i = size_t(y0) * image.width; i < size_t(y1) * image.width; ++i) {
      const float* n = &image.normal[3 * i];
      const float ndl = std::max(0.0f, n[0] * l[0] + n[1] * l[1] + n[2] * l[2]);
      float spec = 0;
      if (o.model == Shading::BlinnPhong && ndl > 0) {
        const float ndh = std::max(0.0f, n[0] * hv[0] + n[1] * hv[1] + n[2] * hv[2]);
        spec = o.specular * o.intensity * std::pow(ndh, o.exponent);
      }
      for (int c = 0; c < 3; ++c) {
        const float a = o.use_albedo ? image.albedo[3 * i + c] : 0.8f;
        out.pixels[3 * i + c] = a * (o.ambient + o.intensity * ndl) + spec;
      }
    }
  });
  return out;
}

Image view_albedo(const Rgbn& image) { return albedo_image(image); }

Image view_normals(const Rgbn& image) {
  Image out(image.width, image.height);
  // The colours of an 8-bit normal map as displayed: (n+1)/2 is the sRGB-encoded value.
  for (size_t i = 0; i < image.normal.size(); ++i)
    out.pixels[i] = srgb_to_linear(std::clamp((image.normal[i] + 1.0f) * 0.5f, 0.0f, 1.0f));
  return out;
}

Image view_needles(const Rgbn& image, int spacing) {
  ShadeOptions so;
  so.use_albedo = false;
  so.light = {0, 0, 1};
  so.ambient = 0.1f;
  so.intensity = 0.6f;
  Image out = shade(image, so);
  spacing = std::max(4, spacing);
  const float len = 0.9f * spacing;
  for (int cy = spacing / 2; cy < image.height; cy += spacing)
    for (int cx = spacing / 2; cx < image.width; cx += spacing) {
      const float* n = image.n(cx, cy);
      // Projected normal: +x right, +y up (rows decrease).
      const float dx = n[0] * len, dy = -n[1] * len;
      const int steps = std::max(1, int(std::ceil(std::max(std::abs(dx), std::abs(dy)))));
      for (int s = 0; s <= steps; ++s) {
        const int x = int(std::lround(cx + dx * s / steps)), y = int(std::lround(cy + dy * s / steps));
        if (x < 0 || y < 0 || x >= image.width || y >= image.height) continue;
        float* p = out.pixel(x, y);
        p[0] = 0.9f, p[1] = 0.05f, p[2] = 0.02f;
      }
      float* p = out.pixel(cx, cy);
      p[0] = p[1] = p[2] = 0.0f;
    }
  return out;
}

Image view_signed(const std::vector<float>& v, int w, int h, float range) {
  if (range <= 0) {
    std::vector<float> a;
    a.reserve(v.size());
    for (float x : v)
      if (std::isfinite(x)) a.push_back(std::abs(x));
    if (!a.empty()) {
      const size_t k = std::min(a.size() - 1, size_t(0.99 * double(a.size())));
      std::nth_element(a.begin(), a.begin() + k, a.end());
      range = a[k];
    }
    if (!(range > 0)) range = 1.0f;
  }
  Image out(w, h);
  for (size_t i = 0; i < v.size(); ++i) {
    const float t = std::clamp(std::isfinite(v[i]) ? v[i] / range : 0.0f, -1.0f, 1.0f);
    float* p = &out.pixels[3 * i];
    if (t >= 0) {
      p[0] = 1.0f, p[1] = 1.0f - t, p[2] = 1.0f - t;
    } else {
      p[0] = 1.0f + t, p[1] = 1.0f + t, p[2] = 1.0f;
    }
  }
  return out;
}

Image view_labels(const std::vector<int>& labels, int w, int h) {
  Image out(w, h);
  for (size_t i = 0; i < labels.size(); ++i) {
    uint32_t s = uint32_t(labels[i]) * 2654435761u + 0x9e3779b9u;
    s ^= s >> 15, s *= 0x2c1b3c6du, s ^= s >> 12;
    for (int c = 0; c < 3; ++c) out.pixels[3 * i + c] = srgb_to_linear(0.25f + 0.7f * float((s >> (8 * c)) & 255) / 255.0f);
  }
  return out;
}

}  // namespace proctex::rgbn
