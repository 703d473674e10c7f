#include "rgbn/edit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>

#include "core/error.h"

namespace proctex::rgbn {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

inline double dot(const Vec3& a, const Vec3& b) { return double(a[0]) * b[0] + double(a[1]) * b[1] + double(a[2]) * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline Vec3 normalized(Vec3 v) {
  const double l = std::sqrt(dot(v, v));
  if (!(l > 1e-20)) return {0, 0, 1};
  return {float(v[0] / l), float(v[1] / l), float(v[2] / l)};
}
inline Vec3 load(const float* p) { return {p[0], p[1], p[2]}; }
inline void store(float* p, const Vec3& v) { p[0] = v[0], p[1] = v[1], p[2] = v[2]; }

// A unit vector perpendicular to a.
Vec3 any_perpendicular(const Vec3& a) {
  const Vec3 e = std::abs(a[0]) < 0.9f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  return normalized(cross(a, e));
}

}  // namespace

Mat3 arc_rotation(const Vec3& a0, const Vec3& b0, double t) {
  const Vec3 a = normalized(a0), b = normalized(b0);
  Vec3 k = cross(a, b);
  const double s = std::sqrt(dot(k, k)), c = dot(a, b);
  const double theta = std::atan2(s, c);
  if (s < 1e-12) k = c > 0 ? Vec3{0, 0, 1} : any_perpendicular(a);
  else k = {float(k[0] / s), float(k[1] / s), float(k[2] / s)};
  const double ang = t * theta;
  const double ca = std::cos(ang), sa = std::sin(ang), C = 1 - ca;
  const double x = k[0], y = k[1], z = k[2];
  return {{{ca + x * x * C, x * y * C - z * sa, x * z * C + y * sa},
           {y * x * C + z * sa, ca + y * y * C, y * z * C - x * sa},
           {z * x * C - y * sa, z * y * C + x * sa, ca + z * z * C}}};
}

Vec3 apply(const Mat3& r, const Vec3& v) {
  Vec3 o;
  for (int i = 0; i < 3; ++i) o[i] = float(r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2]);
  return o;
}

Vec3 slerp(const Vec3& a0, const Vec3& b0, double t) {
  const Vec3 a = normalized(a0), b = normalized(b0);
  const double c = std::clamp(dot(a, b), -1.0, 1.0);
  const double theta = std::acos(c);
  if (theta < 1e-9) return a;
  Vec3 e;  // unit tangent at a towards b
  if (M_PI - theta < 1e-7) {
    e = any_perpendicular(a);
  } else {
    for (int i = 0; i < 3; ++i) e[i] = float(b[i] - c * a[i]);
    e = normalized(e);
  }
  const double phi = t * theta;
  Vec3 r;
  for (int i = 0; i < 3; ++i) r[i] = float(a[i] * std::cos(phi) + e[i] * std::sin(phi));
  return normalized(r);
}

namespace {
Vec3 meridian_point(const Vec3& v, double s) {
  const double rxy = std::hypot(double(v[0]), double(v[1]));
  const double c = std::sqrt(std::max(0.0, 1 - s * s));
  if (rxy < 1e-12) return {float(c), 0.0f, float(s)};
  return {float(v[0] / rxy * c), float(v[1] / rxy * c), float(s)};
}
}  // namespace

Vec3 saturate_on_arc(const Vec3& a0, const Vec3& b0, double xi_deg) {
  const double s = std::sin(xi_deg * M_PI / 180.0);
  const Vec3 a = normalized(a0), b = normalized(b0);
  if (b[2] >= s) return b;
  if (a[2] < s) return meridian_point(b, s);
  // Arc a cos(phi) + e sin(phi), phi in [0, theta]; z(phi) = R cos(phi - phi0) crosses s first at
  // phi0 + acos(s / R) (z decreases there).
  const double c = std::clamp(dot(a, b), -1.0, 1.0), theta = std::acos(c);
  Vec3 e;
  if (M_PI - theta < 1e-7) {
    e = any_perpendicular(a);
  } else {
    for (int i = 0; i < 3; ++i) e[i] = float(b[i] - c * a[i]);
    e = normalized(e);
  }
  const double R = std::hypot(double(a[2]), double(e[2])), phi0 = std::atan2(double(e[2]), double(a[2]));
  double phi = phi0 + std::acos(std::clamp(s / std::max(R, 1e-12), -1.0, 1.0));
  phi = std::clamp(phi, 0.0, theta);
  Vec3 k;
  for (int i = 0; i < 3; ++i) k[i] = float(a[i] * std::cos(phi) + e[i] * std::sin(phi));
  k = normalized(k);
  if (k[2] < s) k = meridian_point(k, s);  // rounding
  return k;
}

void local_frame(const Vec3& n, const Vec3& o, Vec3& u, Vec3& v) {
  const double d = dot(o, n);
  Vec3 t = {float(o[0] - d * n[0]), float(o[1] - d * n[1]), float(o[2] - d * n[2])};
  if (dot(t, t) < 1e-12) t = any_perpendicular(n);
  u = normalized(t);
  v = cross(n, u);
}

// --- helpers -------------------------------------------------------------------------------
namespace {

struct Rect {
  int x = 0, y = 0, w = 0, h = 0;
  bool empty() const { return w <= 0 || h <= 0; }
};

Rect clip(Rect r, int W, int H) {
  const int x0 = std::max(0, r.x), y0 = std::max(0, r.y);
  const int x1 = std::min(W, r.x + r.w), y1 = std::min(H, r.y + r.h);
  return {x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0)};
}

Rect grow(Rect r, int m) { return {r.x - m, r.y - m, r.w + 2 * m, r.h + 2 * m}; }

// Mean |dq/dx - dp/dy| over the interior of a rectangle.
double integrability_in(const Rgbn& im, Rect r) {
  r = clip(r, im.width, im.height);
  double sum = 0;
  size_t count = 0;
  auto pq = [&](int x, int y, float& p, float& q) {
    const float* n = im.n(x, y);
    const float nz = std::max(n[2], 0.05f);
    p = -n[0] / nz, q = -n[1] / nz;
  };
  for (int y = std::max(1, r.y); y < std::min(im.height - 1, r.y + r.h); ++y)
    for (int x = std::max(1, r.x); x < std::min(im.width - 1, r.x + r.w); ++x) {
      float pl, ql, pr, qr, pu, qu, pd, qd;
      pq(x - 1, y, pl, ql), pq(x + 1, y, pr, qr), pq(x, y - 1, pu, qu), pq(x, y + 1, pd, qd);
      sum += std::abs(0.5 * (qr - ql) - 0.5 * (pu - pd));
      ++count;
    }
  return count ? sum / double(count) : 0.0;
}

double num(const json& op, const char* key, double fallback) {
  if (!op.contains(key)) return fallback;
  if (!op[key].is_number()) throw UsageError(std::string("edit parameter '") + key + "' must be a number", "see 'proctex rgbn edit --help'");
  const double v = op[key].get<double>();
  if (!std::isfinite(v)) throw UsageError(std::string("edit parameter '") + key + "' is not finite", "give a finite number");
  return v;
}

std::string str(const json& op, const char* key, const std::string& fallback) {
  if (!op.contains(key)) return fallback;
  if (!op[key].is_string()) throw UsageError(std::string("edit parameter '") + key + "' must be a string", "see 'proctex rgbn edit --help'");
  return op[key].get<std::string>();
}

std::vector<double> numbers(const json& v, size_t n, const char* what) {
  if (!v.is_array() || v.size() != n)
    throw UsageError(std::string("'") + what + "' must be an array of " + std::to_string(n) + " numbers", "see 'proctex rgbn edit --help'");
  std::vector<double> out;
  for (const auto& x : v) {
    if (!x.is_number() || !std::isfinite(x.get<double>()))
      throw UsageError(std::string("'") + what + "' holds a value that is not a finite number", "see 'proctex rgbn edit --help'");
    out.push_back(x.get<double>());
  }
  return out;
}

// The region's weight per pixel over its bounding box (weights outside the box are 0).
struct Region {
  Rect box;
  std::vector<float> weight;  // box.w * box.h
  float at(int x, int y) const {
    if (x < box.x || y < box.y || x >= box.x + box.w || y >= box.y + box.h) return 0.0f;
    return weight[size_t(y - box.y) * box.w + (x - box.x)];
  }
  // Distance-based falloff for blend mode: 1 at the centre, 0 at the rim (discs), else weight.
  std::vector<float> falloff;
  float fade(int x, int y) const {
    if (falloff.empty()) return at(x, y);
    return falloff[size_t(y - box.y) * box.w + (x - box.x)];
  }
};

Region parse_region(const json& op, const Rgbn& im, const fs::path& base_dir) {
  Region r;
  if (!op.contains("region") || op["region"].is_null()) {
    r.box = {0, 0, im.width, im.height};
    r.weight.assign(im.size(), 1.0f);
    return r;
  }
  const json& g = op["region"];
  if (!g.is_object()) throw UsageError("'region' must be an object", "e.g. {\"disc\":[64,64,20]}");
  if (g.contains("disc")) {
    const auto d = numbers(g["disc"], 3, "region.disc");
    const double feather = g.contains("feather") ? num(g, "feather", 0) : 0.0;
    if (!(d[2] > 0)) throw UsageError("region disc radius must be positive", "e.g. {\"disc\":[64,64,20]}");
    r.box = clip(Rect{int(std::floor(d[0] - d[2])), int(std::floor(d[1] - d[2])), int(std::ceil(2 * d[2])) + 2,
                      int(std::ceil(2 * d[2])) + 2}, im.width, im.height);
    r.weight.assign(size_t(r.box.w) * r.box.h, 0.0f);
    r.falloff.assign(r.weight.size(), 0.0f);
    for (int y = 0; y < r.box.h; ++y)
      for (int x = 0; x < r.box.w; ++x) {
        const double dist = std::hypot(r.box.x + x - d[0], r.box.y + y - d[1]);
        if (dist > d[2]) continue;
        float w = 1.0f;
        if (feather > 0 && dist > d[2] - feather) {
          const float t = float((d[2] - dist) / feather);
          w = t * t * (3 - 2 * t);
        }
        r.weight[size_t(y) * r.box.w + x] = w;
        const float t = float(1 - dist / d[2]);
        r.falloff[size_t(y) * r.box.w + x] = t * t * (3 - 2 * t);
      }
    return r;
  }
  if (g.contains("rect")) {
    const auto v = numbers(g["rect"], 4, "region.rect");
    r.box = clip(Rect{int(v[0]), int(v[1]), int(v[2]), int(v[3])}, im.width, im.height);
    r.weight.assign(size_t(r.box.w) * r.box.h, 1.0f);
    return r;
  }
  if (g.contains("mask")) {
    if (!g["mask"].is_string()) throw UsageError("region.mask must be a file name", "e.g. {\"mask\":\"brush.png\"}");
    fs::path p = g["mask"].get<std::string>();
    if (p.is_relative() && !base_dir.empty()) p = base_dir / p;
    const Mask m = image_mask(load_image(p), im.width, im.height);
    r.box = {0, 0, im.width, im.height};
    r.weight = m;
    return r;
  }
  throw UsageError("unknown region " + g.dump(), "use {\"disc\":[x,y,r]}, {\"rect\":[x,y,w,h]} or {\"mask\":\"file.png\"}");
}

// Keeps n_z >= sin(xi) along the arc from the old normal to the new one.
// Base normals of a footprint for stamps and pens ("base_sigma" > 0): a bilateral-smoothed copy
// of the normals (Pereira & Velho's base), computed on the footprint grown by the filter's reach,
// so that a stamp replaces the detail under it instead of riding on it.
struct BaseField {
  Rect r;
  Rgbn im;
  bool on = false;
  Vec3 at(const Rgbn& src, int x, int y) const {
    return on ? Vec3{im.n(x - r.x, y - r.y)[0], im.n(x - r.x, y - r.y)[1], im.n(x - r.x, y - r.y)[2]}
              : Vec3{src.n(x, y)[0], src.n(x, y)[1], src.n(x, y)[2]};
  }
};
BaseField base_field(const Rgbn& im, const json& op, Rect foot) {
  BaseField b;
  const double sigma = num(op, "base_sigma", 0);
  if (sigma == 0) return b;
  if (!(sigma > 0 && sigma <= 32)) throw UsageError("base_sigma must be in (0, 32] pixels (0 = the current normals)", "e.g. \"base_sigma\":3");
  b.on = true;
  b.r = clip(grow(foot, int(std::ceil(2 * sigma)) + 1), im.width, im.height);
  Rgbn crop(std::max(1, b.r.w), std::max(1, b.r.h));
  for (int y = 0; y < b.r.h; ++y)
    for (int x = 0; x < b.r.w; ++x) {
      std::copy_n(im.n(b.r.x + x, b.r.y + y), 3, crop.n(x, y));
      std::copy_n(im.a(b.r.x + x, b.r.y + y), 3, crop.a(x, y));
    }
  const double sigma_n = num(op, "base_sigma_n", 0.5);
  if (!(sigma_n > 0 && sigma_n <= 10)) throw UsageError("base_sigma_n must be in (0, 10]", "e.g. \"base_sigma_n\":0.5");
  BilateralOptions bo;  // a wide normal range: fine detail is smoothed, strong creases survive
  bo.sigma_s = float(sigma);
  bo.sigma_n = float(sigma_n);
  bo.albedo = false;
  b.im = bilateral(crop, bo);
  return b;
}

inline Vec3 bound(const Vec3& before, const Vec3& after, double xi) {
  if (xi <= -90) return after;
  return saturate_on_arc(before, after, xi);
}

Rgbn load_stamp(const json& op, const fs::path& base_dir) {
  Rgbn s;
  if (op.contains("file")) {
    fs::path p = str(op, "file", "");
    if (p.is_relative() && !base_dir.empty()) p = base_dir / p;
    s = load_rgbn(p);
  } else {
    s = stamp_shape(str(op, "shape", "dome"), float(num(op, "radius", 16)), float(num(op, "height", 6)));
  }
  if (op.contains("detail")) {
    const auto d = numbers(op["detail"], 2, "detail");
    FilterOptions fo;
    fo.kind = FilterKind::Detail;
    fo.sigma = float(d[0]), fo.sigma2 = float(d[1]);
    s = filter(s, fo);
  }
  return s;
}

void bilinear(const Rgbn& s, double x, double y, Vec3& n, Vec3& a) {
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  double sn[3] = {0, 0, 0}, sa[3] = {0, 0, 0};
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      const int xx = std::clamp(x0 + i, 0, s.width - 1), yy = std::clamp(y0 + j, 0, s.height - 1);
      const double w = (i ? fx : 1 - fx) * (j ? fy : 1 - fy);
      for (int c = 0; c < 3; ++c) sn[c] += w * s.n(xx, yy)[c], sa[c] += w * s.a(xx, yy)[c];
    }
  n = normalized({float(sn[0]), float(sn[1]), float(sn[2])});
  a = {float(sa[0]), float(sa[1]), float(sa[2])};
}

}  // namespace

Rgbn stamp_shape(const std::string& shape, float radius, float height) {
  if (!(radius >= 1 && radius <= 4096)) throw UsageError("stamp radius must be in [1, 4096] pixels", "e.g. \"radius\":16");
  if (!std::isfinite(height)) throw UsageError("stamp height must be finite", "e.g. \"height\":6");
  const int size = 2 * int(std::ceil(radius)) + 3;
  const float c = 0.5f * float(size - 1);
  HeightField hf{size, size, std::vector<float>(size_t(size) * size, 0.0f)};
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const float r = std::hypot(x - c, y - c) / radius;
      float h = 0;
      if (shape == "dome" || shape == "dimple") {
        h = r < 1 ? (1 - r * r) * (1 - r * r) : 0.0f;
        if (shape == "dimple") h = -h;
      } else if (shape == "ring") {
        h = r < 1 ? std::pow(std::sin(float(M_PI) * r), 2.0f) : 0.0f;
      } else {
        throw UsageError("unknown stamp shape '" + shape + "'", "use dome, dimple or ring, or give \"file\"");
      }
      hf.at(x, y) = height * h;
    }
  return from_height(hf, 1.0f, false);
}

EditReport apply_edit(Rgbn& im, const json& op, const fs::path& base_dir) {
  const auto start = std::chrono::steady_clock::now();
  if (!op.is_object() || !op.contains("op") || !op["op"].is_string())
    throw UsageError("an edit must be a JSON object with a string \"op\": " + op.dump().substr(0, 80),
                     "e.g. {\"op\":\"stamp\",\"at\":[64,64]}");
  EditReport rep;
  rep.op = op["op"].get<std::string>();
  const double xi = num(op, "xi", -90);
  if (xi > 89) throw UsageError("xi must be below 89 degrees", "e.g. \"xi\": 15");
  Rect foot;
  // Measures integrability on the footprint before changing it.
  auto begin = [&](Rect r) {
    foot = clip(r, im.width, im.height);
    rep.footprint = {foot.x, foot.y, foot.w, foot.h};
    rep.integrability_before = integrability_in(im, grow(foot, 1));
  };
  const Vec3 x_axis = {1, 0, 0};

  if (rep.op == "rotate") {
    const auto t = numbers(op.value("target", json::array({0, 0, 1})), 3, "target");
    const Vec3 target = normalized({float(t[0]), float(t[1]), float(t[2])});
    const double amount = num(op, "amount", 1.0);
    const std::string mode = str(op, "mode", "replace");
    if (mode != "replace" && mode != "blend") throw UsageError("rotate mode must be replace or blend", "e.g. \"mode\":\"blend\"");
    const Region reg = parse_region(op, im, base_dir);
    begin(reg.box);
    for (int y = foot.y; y < foot.y + foot.h; ++y)
      for (int x = foot.x; x < foot.x + foot.w; ++x) {
        const float w = mode == "blend" ? reg.fade(x, y) : reg.at(x, y);
        if (w <= 0) continue;
        const Vec3 n0 = load(im.n(x, y));
        const Vec3 n1 = bound(n0, slerp(n0, target, amount * w), xi);
        store(im.n(x, y), n1);
        ++rep.pixels_changed;
      }
  } else if (rep.op == "stamp") {
    const Rgbn s = load_stamp(op, base_dir);
    const auto at = numbers(op.value("at", json()), 2, "at");
    const double angle = num(op, "angle", 0) * M_PI / 180.0, scale = num(op, "scale", 1.0);
    const double strength = num(op, "strength", 1.0);
    const std::string albedo = str(op, "albedo", op.contains("file") ? "replace" : "keep");
    if (albedo != "keep" && albedo != "replace" && albedo != "multiply")
      throw UsageError("stamp albedo must be keep, replace or multiply", "e.g. \"albedo\":\"keep\"");
    if (!(scale > 0.01 && scale < 100)) throw UsageError("stamp scale must be in (0.01, 100)", "e.g. \"scale\":1");
    const double half = 0.5 * std::hypot(s.width, s.height) * scale;
    begin(Rect{int(std::floor(at[0] - half)), int(std::floor(at[1] - half)), int(std::ceil(2 * half)) + 2,
               int(std::ceil(2 * half)) + 2});
    const BaseField base = base_field(im, op, foot);
    const double ca = std::cos(angle), sa = std::sin(angle);
    const Vec3 o = {float(ca), float(sa), 0.0f};  // the stamp's +x axis in the image (y up)
    const double scx = 0.5 * (s.width - 1), scy = 0.5 * (s.height - 1);
    for (int y = foot.y; y < foot.y + foot.h; ++y)
      for (int x = foot.x; x < foot.x + foot.w; ++x) {
        // Image offset (y up), rotated into the stamp frame.
        const double dx = x - at[0], dy = at[1] - y;
        const double sx = (ca * dx + sa * dy) / scale, sy = (-sa * dx + ca * dy) / scale;
        const double px = scx + sx, py = scy - sy;
        if (px < -0.5 || py < -0.5 || px > s.width - 0.5 || py > s.height - 0.5) continue;
        Vec3 t, a;
        bilinear(s, px, py, t, a);
        if (strength != 1.0) t = normalized({float(t[0] * strength), float(t[1] * strength), t[2]});
        const Vec3 n0 = load(im.n(x, y)), b = base.at(im, x, y);
        Vec3 u, v;
        local_frame(b, o, u, v);
        Vec3 n1 = normalized({t[0] * u[0] + t[1] * v[0] + t[2] * b[0], t[0] * u[1] + t[1] * v[1] + t[2] * b[1],
                              t[0] * u[2] + t[1] * v[2] + t[2] * b[2]});
        n1 = bound(n0, n1, xi);
        store(im.n(x, y), n1);
        float* alb = im.a(x, y);
        if (albedo == "replace") store(alb, a);
        else if (albedo == "multiply") alb[0] *= a[0], alb[1] *= a[1], alb[2] *= a[2];
        ++rep.pixels_changed;
      }
  } else if (rep.op == "pen") {
    if (!op.contains("points") || !op["points"].is_array() || op["points"].empty())
      throw UsageError("pen needs \"points\": [[x,y], ...]", "e.g. \"points\":[[10,10],[100,40]]");
    std::vector<std::array<double, 2>> pts;
    for (const auto& p : op["points"]) {
      const auto v = numbers(p, 2, "points[i]");
      pts.push_back({v[0], v[1]});
    }
    if (pts.size() == 1) pts.push_back(pts[0]);
    const double width = num(op, "width", 6), depth = num(op, "depth", 2);
    const std::string profile = str(op, "profile", "groove");
    if (profile != "groove" && profile != "ridge" && profile != "vee")
      throw UsageError("pen profile must be groove, ridge or vee", "e.g. \"profile\":\"vee\"");
    if (!(width > 0 && width < 1000)) throw UsageError("pen width must be in (0, 1000) pixels", "e.g. \"width\":6");
    double x0 = 1e30, y0 = 1e30, x1 = -1e30, y1 = -1e30;
    for (const auto& p : pts) x0 = std::min(x0, p[0]), y0 = std::min(y0, p[1]), x1 = std::max(x1, p[0]), y1 = std::max(y1, p[1]);
    begin(Rect{int(std::floor(x0 - width)) - 1, int(std::floor(y0 - width)) - 1, int(std::ceil(x1 - x0 + 2 * width)) + 3,
               int(std::ceil(y1 - y0 + 2 * width)) + 3});
    const BaseField base = base_field(im, op, foot);
    for (int y = foot.y; y < foot.y + foot.h; ++y)
      for (int x = foot.x; x < foot.x + foot.w; ++x) {
        double best = 1e30, nx = 0, ny = 0;
        for (size_t k = 0; k + 1 < pts.size(); ++k) {
          const double ax = pts[k][0], ay = pts[k][1], bx = pts[k + 1][0], by = pts[k + 1][1];
          const double vx = bx - ax, vy = by - ay, len2 = vx * vx + vy * vy;
          const double t = len2 > 0 ? std::clamp(((x - ax) * vx + (y - ay) * vy) / len2, 0.0, 1.0) : 0.0;
          const double cx = ax + t * vx, cy = ay + t * vy;
          const double d2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
          if (d2 < best) best = d2, nx = cx, ny = cy;
        }
        const double s = std::sqrt(best);
        if (s >= width) continue;
        const double u = s / width;
        double dh;  // h'(s)
        if (profile == "vee") dh = depth / width;
        else dh = 4 * depth * u * (1 - u * u) / width * (profile == "groove" ? 1 : -1);
        Vec3 t = {0, 0, 1};
        if (s > 1e-9) {
          const double gx = dh * (x - nx) / s, gy = dh * (ny - y) / s;  // height gradient, y up
          t = normalized({float(-gx), float(-gy), 1.0f});
        }
        const Vec3 n0 = load(im.n(x, y)), b = base.at(im, x, y);
        Vec3 e1, e2;
        local_frame(b, x_axis, e1, e2);
        Vec3 n1 = normalized({t[0] * e1[0] + t[1] * e2[0] + t[2] * b[0], t[0] * e1[1] + t[1] * e2[1] + t[2] * b[1],
                              t[0] * e1[2] + t[1] * e2[2] + t[2] * b[2]});
        store(im.n(x, y), bound(n0, n1, xi));
        ++rep.pixels_changed;
      }
  } else if (rep.op == "filter") {
    const Region reg = parse_region(op, im, base_dir);
    begin(reg.box);
    const std::string kind = str(op, "filter", "smooth");
    const float sigma = float(num(op, "sigma", 2)), sigma2 = float(num(op, "sigma2", 6));
    const int margin = int(std::ceil(3 * std::max(sigma, sigma2))) + 2;
    const Rect work = clip(grow(foot, margin), im.width, im.height);
    Rgbn crop(work.w, work.h);
    for (int y = 0; y < work.h; ++y) {
      std::copy(im.n(work.x, work.y + y), im.n(work.x, work.y + y) + 3 * work.w, crop.n(0, y));
      std::copy(im.a(work.x, work.y + y), im.a(work.x, work.y + y) + 3 * work.w, crop.a(0, y));
    }
    Rgbn out;
    if (kind == "bilateral") {
      BilateralOptions bo;
      bo.sigma_s = sigma;
      bo.sigma_c = float(num(op, "sigma_c", bo.sigma_c));
      bo.sigma_n = float(num(op, "sigma_n", bo.sigma_n));
      out = bilateral(crop, bo);
    } else {
      FilterOptions fo;
      fo.kind = parse_filter_kind(kind);
      fo.sigma = sigma, fo.sigma2 = sigma2;
      fo.amount = float(num(op, "amount", 1));
      fo.albedo = op.value("albedo", false);
      out = filter(crop, fo);
    }
    for (int y = foot.y; y < foot.y + foot.h; ++y)
      for (int x = foot.x; x < foot.x + foot.w; ++x) {
        const float m = std::clamp(reg.at(x, y), 0.0f, 1.0f);
        if (m <= 0) continue;
        const Vec3 n0 = load(im.n(x, y));
        const float* f = out.n(x - work.x, y - work.y);
        Vec3 n1 = normalized({n0[0] + m * (f[0] - n0[0]), n0[1] + m * (f[1] - n0[1]), n0[2] + m * (f[2] - n0[2])});
        store(im.n(x, y), bound(n0, n1, xi));
        const float* fa = out.a(x - work.x, y - work.y);
        float* a = im.a(x, y);
        for (int c = 0; c < 3; ++c) a[c] += m * (fa[c] - a[c]);
        ++rep.pixels_changed;
      }
  } else if (rep.op == "saturate") {
    if (!op.contains("xi")) throw UsageError("saturate needs \"xi\" (degrees)", "e.g. {\"op\":\"saturate\",\"xi\":20}");
    const Region reg = parse_region(op, im, base_dir);
    begin(reg.box);
    const double s = std::sin(xi * M_PI / 180.0);
    for (int y = foot.y; y < foot.y + foot.h; ++y)
      for (int x = foot.x; x < foot.x + foot.w; ++x) {
        if (reg.at(x, y) <= 0) continue;
        const Vec3 n0 = load(im.n(x, y));
        if (n0[2] >= s) continue;
        store(im.n(x, y), meridian_point(n0, s));
        ++rep.pixels_changed;
      }
  } else if (rep.op == "paint") {
    const auto c = numbers(op.value("color", json()), 3, "color");
    const std::string mode = str(op, "mode", "replace");
    const double opacity = std::clamp(num(op, "opacity", 1.0), 0.0, 1.0);
    if (mode != "replace" && mode != "multiply") throw UsageError("paint mode must be replace or multiply", "e.g. \"mode\":\"multiply\"");
    const Region reg = parse_region(op, im, base_dir);
    begin(reg.box);
    for (int y = foot.y; y < foot.y + foot.h; ++y)
      for (int x = foot.x; x < foot.x + foot.w; ++x) {
        const float w = float(opacity) * reg.at(x, y);
        if (w <= 0) continue;
        float* a = im.a(x, y);
        for (int k = 0; k < 3; ++k) {
          const float target = mode == "replace" ? float(c[k]) : a[k] * float(c[k]);
          a[k] += w * (target - a[k]);
        }
        ++rep.pixels_changed;
      }
  } else {
    throw UsageError("unknown edit op '" + rep.op + "'", "use rotate, stamp, pen, filter, saturate or paint");
  }
  rep.integrability_after = integrability_in(im, grow(foot, 1));
  rep.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return rep;
}

Rgbn apply_edits(const Rgbn& source, const json& session, std::vector<EditReport>* reports, const fs::path& base_dir,
                 int upto) {
  const json* ops = &session;
  if (session.is_object()) {
    if (!session.contains("ops")) throw UsageError("an edit session is a JSON array of ops or an object with \"ops\"", "e.g. [{\"op\":\"stamp\",\"at\":[64,64]}]");
    ops = &session["ops"];
  }
  if (!ops->is_array()) throw UsageError("an edit session is a JSON array of ops", "e.g. [{\"op\":\"stamp\",\"at\":[64,64]}]");
  Rgbn out = source;
  int k = 0;
  for (const auto& op : *ops) {
    if (upto >= 0 && k >= upto) break;
    EditReport r;
    try {
      r = apply_edit(out, op, base_dir);
    } catch (const UsageError& e) {
      throw UsageError("edit " + std::to_string(k + 1) + ": " + e.message(), e.hint());
    } catch (const Error& e) {
      throw Error("edit " + std::to_string(k + 1) + ": " + e.message(), e.hint());
    }
    if (reports) reports->push_back(r);
    ++k;
  }
  return out;
}

json to_json(const EditReport& r) {
  return {{"op", r.op},
          {"pixels_changed", r.pixels_changed},
          {"footprint", r.footprint},
          {"integrability_before", r.integrability_before},
          {"integrability_after", r.integrability_after},
          {"milliseconds", r.milliseconds}};
}

}  // namespace proctex::rgbn
