#include "synth/render.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <future>
#include <memory>
#include <thread>

#include <fmt/format.h>

#include "core/error.h"
#include "image/io.h"
#include "synth/timing.h"

namespace proctex::synth {
namespace fs = std::filesystem;
namespace {

std::string ext_of(const fs::path& p) {
  std::string e = p.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// The pixel type written for a file: PNG 8/16, JPEG 8, TIFF 8/16, EXR half (colour) or float (coords).
PixelType file_type(const fs::path& p, int bits) {
  const std::string e = ext_of(p);
  if (e == ".exr") return PixelType::Half;
  if (e == ".jpg" || e == ".jpeg") return PixelType::UInt8;
  if (e == ".png") return bits == 16 ? PixelType::UInt16 : PixelType::UInt8;
  if (e == ".tif" || e == ".tiff") return bits == 8 ? PixelType::UInt8 : PixelType::UInt16;
  throw UsageError(fmt::format("cannot write '{}': unknown extension", p.string()), "use .png, .tif, .exr or .jpg");
}

// Every texel of the source encoded once in the file's pixel type: a strip is then a gather.
struct Palette {
  PixelType type;
  size_t texel_bytes = 0;
  std::vector<unsigned char> bytes;
  // 8-bit palettes: each texel's three codes in 21-bit lanes of one integer (c0 | c1 << 21 |
  // c2 << 42), so the seam blend adds a weighted texel with one multiply-add; a lane holds up to
  // 2^21 - 1 >= 255 (R + 1)^4 for blend radii R <= 8, so the lanes never carry into each other.
  std::vector<uint64_t> packed;
};

Palette make_palette(const Image& src, PixelType type) {
  Palette p;
  const size_t n = static_cast<size_t>(src.width) * src.height;
  if (type == PixelType::Half) {
    p.type = PixelType::Float;  // the writer converts float to half
    p.texel_bytes = 3 * sizeof(float);
    p.bytes.resize(n * p.texel_bytes);
    std::memcpy(p.bytes.data(), src.pixels.data(), p.bytes.size());
    return p;
  }
  const bool wide = type == PixelType::UInt16;
  p.type = type;
  p.texel_bytes = 3 * (wide ? 2 : 1);
  p.bytes.resize(n * p.texel_bytes);
  const double levels = wide ? 65535.0 : 255.0;
  for (size_t i = 0; i < 3 * n; ++i) {
    const double code = std::round(linear_to_srgb(std::clamp(src.pixels[i], 0.0f, 1.0f)) * levels);
    if (wide) {
      const uint16_t v = static_cast<uint16_t>(code);
      std::memcpy(&p.bytes[i * 2], &v, 2);
    } else {
      p.bytes[i] = static_cast<unsigned char>(code);
    }
  }
  if (!wide) {
    p.packed.resize(n);
    for (size_t t = 0; t < n; ++t)
      p.packed[t] = uint64_t(p.bytes[3 * t]) | uint64_t(p.bytes[3 * t + 1]) << 21 | uint64_t(p.bytes[3 * t + 2]) << 42;
  }
  return p;
}

// One output file written strip by strip into a temporary (image/io.h); commit() renames it into
// place, the destructor removes an uncommitted temporary.
class StripFile {
 public:
  StripFile(fs::path target, int width, int height, PixelType file_format, bool linear, int png_level = 1) {
    WriteOptions options;
    options.file_type = file_format;
    options.colour_space = linear ? "Linear" : "sRGB";
    if (ext_of(target) == ".png") {
      options.png_compression_level = png_level;
      if (png_level == 1) options.png_filter = 0x10;  // libpng's PNG_FILTER_SUB (see RenderOutputs)
    }
    writer_ = std::make_unique<StripWriter>(target, width, height, options);
  }
  void write(int y0, int rows, PixelType type, const void* data) { writer_->write_rows(y0, rows, type, data); }
  void close() { writer_->close(); }
  void commit() { writer_->finish(); }

 private:
  std::unique_ptr<StripWriter> writer_;
};

void check_folder(const fs::path& p) {
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error(fmt::format("cannot write '{}': folder '{}' does not exist", p.string(), dir.string()),
                "create the folder first or choose another output path");
  }
}

// Seam blending over a (2R + 1)^2 neighbourhood: output pixel p is the weighted mean of the texels
// its neighbours p + d predict for it, E[S(p + d) - d] (|dx|, |dy| <= R), with the tent weights
// (R + 1 - |dx|)(R + 1 - |dy|): the weight falls with the distance from p, so across a join the
// colour ramps from one patch to the other over 2R pixels. P holds the coordinates of the strip
// padded by R on every side (pw wide). A prediction that leaves a bounded exemplar is skipped.
// Averaged in the palette's own encoding (codes for 8/16 bit, linear floats for EXR), rounded to
// the nearest code; normals are averaged as vectors (decoded from the sRGB-encoded (n + 1) / 2 like
// the matching does) and renormalised. Inside a patch all predictions are one texel and the result
// is that texel's bytes. Deterministic: a fixed summation order, independent of strips and threads.
struct SeamBlend {
  int radius = 1;
  int ew = 0, eh = 0;
  bool toroidal = false;
  std::vector<int> dx, dy, weight;  // the taps, centre first
  SeamBlend(int r, int w, int h, bool torus) : radius(r), ew(w), eh(h), toroidal(torus) {
    dx.push_back(0), dy.push_back(0), weight.push_back((r + 1) * (r + 1));
    for (int y = -r; y <= r; ++y)
      for (int x = -r; x <= r; ++x)
        if (x != 0 || y != 0) dx.push_back(x), dy.push_back(y), weight.push_back((r + 1 - std::abs(x)) * (r + 1 - std::abs(y)));
  }
  // The texels the taps predict for pixel (x, y) of the inner region; -1 = outside the exemplar.
  // Returns true when every valid prediction is the centre's (the pixel is inside a patch).
  bool predict(const std::vector<int32_t>& P, int pw, int x, int y, int32_t* pred) const {
    bool same = true;
    for (size_t k = 0; k < dx.size(); ++k) {
      const size_t i = static_cast<size_t>(y + radius + dy[k]) * pw + (x + radius + dx[k]);
      int ux = P[2 * i] - dx[k], uy = P[2 * i + 1] - dy[k];
      if (toroidal) {
        ux = ux < 0 ? ux + ew : ux >= ew ? ux - ew : ux;
        uy = uy < 0 ? uy + eh : uy >= eh ? uy - eh : uy;
      } else if (ux < 0 || uy < 0 || ux >= ew || uy >= eh) {
        pred[k] = -1;
        continue;
      }
      pred[k] = uy * ew + ux;
      same = same && pred[k] == pred[0];
    }
    return same;
  }
};

// The blend's working memory, kept across calls: allocated anew for every chunk, its pages were
// faulted in and zeroed again each time (~1 ms CPU per 512^2 output).
struct BlendScratch {
  std::vector<int32_t> sum, run_end;
};

// Blends output rows [ya, yb) of the strip (`rows` rows) into `out` (the whole strip's bytes).
void blend_strip(const Palette& pal, bool normal, const SeamBlend& sb, const std::vector<int32_t>& P, int pw, int w,
                 int rows, std::vector<unsigned char>& out, int ya, int yb, BlendScratch& scratch) {
  const size_t tb = pal.texel_bytes;
  const bool wide = pal.type == PixelType::UInt16, flt = pal.type == PixelType::Float;
  const double levels = wide ? 65535.0 : 255.0;
  auto value = [&](int32_t texel, int c) -> double {  // the texel's channel in the palette's encoding
    const unsigned char* b = &pal.bytes[static_cast<size_t>(texel) * tb];
    if (flt) {
      float f;
      std::memcpy(&f, b + 4 * c, 4);
      return f;
    }
    if (wide) {
      uint16_t v;
      std::memcpy(&v, b + 2 * c, 2);
      return v;
    }
    return b[c];
  };
  auto to_unit = [&](double v) {  // palette value -> sRGB-encoded [0, 1]
    return flt ? static_cast<double>(linear_to_srgb(std::clamp(static_cast<float>(v), 0.0f, 1.0f))) : v / levels;
  };
  auto from_unit = [&](double u) {  // sRGB-encoded [0, 1] -> palette value
    return flt ? static_cast<double>(srgb_to_linear(static_cast<float>(u))) : u * levels;
  };
  // Fast path: a pixel whose whole window lies inside one patch (every pair of adjacent pixels in it
  // continues the patch) copies its texel; the same result as predict() finding all predictions
  // equal, without the (2R + 1)^2 predictions. `join` marks a padded pixel that does not continue
  // the patch of its right or lower neighbour; `sum` is its summed-area table.
  const int R = sb.radius, ph = rows + 2 * R;
  // The summed-area table covers the padded rows the output rows [ya, yb) read: [ya, yb + 2R].
  const int sy0 = ya, sh = (yb - ya) + 2 * R;
  auto continues = [&](size_t a, size_t b, int dx, int dy) {  // S[b] = S[a] + (dx, dy) in the exemplar
    int ux = P[2 * b] - dx, uy = P[2 * b + 1] - dy;
    if (sb.toroidal) {
      ux = ux < 0 ? ux + sb.ew : ux >= sb.ew ? ux - sb.ew : ux;
      uy = uy < 0 ? uy + sb.eh : uy >= sb.eh ? uy - sb.eh : uy;
    } else if (ux < 0 || uy < 0 || ux >= sb.ew || uy >= sb.eh) {
      return false;
    }
    return ux == P[2 * a] && uy == P[2 * a + 1];
  };
  std::vector<int32_t>& sum = scratch.sum;
  sum.resize(static_cast<size_t>(pw + 1) * (sh + 1));
  std::fill_n(sum.begin(), pw + 1, 0);  // row 0 and column 0 are zero; the rest is written below
  // Per padded pixel, where its run ends (8/16-bit colour only): the first pixel at or right of it
  // whose right neighbour does not continue its patch. All pixels of a run predict the same texel
  // for a given output pixel, so a window row is summed run by run.
  const bool integer_path = !flt && !normal;
  std::vector<int32_t>& run_end = scratch.run_end;
  run_end.resize(integer_path ? static_cast<size_t>(pw) * sh : 0);
  for (int ly = 0; ly < sh; ++ly) {
    const int y = sy0 + ly;
    int32_t row = 0;
    sum[static_cast<size_t>(ly + 1) * (pw + 1)] = 0;  // column 0
    for (int x = 0; x < pw; ++x) {
      const size_t a = static_cast<size_t>(y) * pw + x;
      const bool hj = x + 1 < pw && !continues(a, a + 1, 1, 0);
      const bool join = hj || (y + 1 < ph && !continues(a, a + pw, 0, 1));
      row += join ? 1 : 0;
      sum[static_cast<size_t>(ly + 1) * (pw + 1) + x + 1] = sum[static_cast<size_t>(ly) * (pw + 1) + x + 1] + row;
      if (integer_path) run_end[static_cast<size_t>(ly) * pw + x] = hj ? x : -1;
    }
    if (integer_path) {
      int32_t* re = &run_end[static_cast<size_t>(ly) * pw];
      int32_t end = pw - 1;
      for (int x = pw - 1; x >= 0; --x) {
        if (re[x] >= 0) end = x;
        re[x] = end;
      }
    }
  }
  // Prefix sums of the horizontal tent weights: taps dx in [a, b] (k = dx + R) weigh tent[b + 1] - tent[a].
  std::vector<int64_t> tent(2 * R + 2, 0);
  for (int k = 0; k <= 2 * R; ++k) tent[k + 1] = tent[k] + (R + 1 - std::abs(k - R));
  auto joins_in_window = [&](int x, int y) {  // inner (x, y): padded window [x, x + 2R] x [y, y + 2R]
    const size_t x0 = x, x1 = x + 2 * R + 1, y0 = y - sy0, y1 = y - sy0 + 2 * R + 1;
    return sum[y1 * (pw + 1) + x1] - sum[y0 * (pw + 1) + x1] - sum[y1 * (pw + 1) + x0] + sum[y0 * (pw + 1) + x0];
  };
  // Every texel's channels as summed: the palette value, or the decoded normal component.
  const size_t texels = flt || normal ? pal.bytes.size() / tb : 0;  // 8/16-bit colour sums the codes
  std::vector<double> term(3 * texels);
  for (size_t t = 0; t < texels; ++t)
    for (int c = 0; c < 3; ++c) {
      const double v = value(static_cast<int32_t>(t), c);
      term[3 * t + c] = normal ? 2.0 * to_unit(v) - 1.0 : v;
    }
  // Rows are independent: they are split over threads (the bytes do not depend on the split).
  auto blend_rows = [&](int ya, int yb) {
  std::vector<int32_t> pred(sb.dx.size());
  for (int y = ya; y < yb; ++y) {
    for (int x = 0; x < w; ++x) {
      unsigned char* dst = &out[(static_cast<size_t>(y) * w + x) * tb];
      if (joins_in_window(x, y) == 0) {
        const size_t c = static_cast<size_t>(y + R) * pw + (x + R);
        const size_t texel = static_cast<size_t>(P[2 * c + 1]) * sb.ew + P[2 * c];
        std::memcpy(dst, &pal.bytes[texel * tb], tb);
        continue;
      }
      if (integer_path) {
        // 8/16-bit codes: the weighted sum is an exact integer, and (2 sum + W) / 2W is
        // lround(sum / W) (the same bytes as the floating-point path, at a fraction of the cost).
        // Adjacent taps of a window row that continue one patch predict the same texel: each run of
        // them adds that texel once with the run's summed weight - the same integer sum as tap by
        // tap, with 1-3 texel reads per row instead of 2R + 1. (Three scalar accumulators: summing into an array kept it in memory, a
        // store-to-load chain that cost a third of the blend.)
        int64_t s0 = 0, s1 = 0, s2 = 0, iweight = 0;
        uint64_t lanes = 0;  // 8-bit codes in 21-bit lanes (Palette::packed)
        const bool swar = !wide && R <= 8;
        const uint64_t* packed = pal.packed.data();
        int64_t first = -1;
        bool same = true;
        const unsigned char* bytes = pal.bytes.data();
        auto add = [&](int yy, int xx, int ddx, int ddy, int64_t wk) __attribute__((always_inline)) {  // padded (xx, yy), tap (ddx, ddy)
          const size_t i = static_cast<size_t>(yy) * pw + xx;
          int ux = P[2 * i] - ddx, uy = P[2 * i + 1] - ddy;
          if (sb.toroidal) {
            ux = ux < 0 ? ux + sb.ew : ux >= sb.ew ? ux - sb.ew : ux;
            uy = uy < 0 ? uy + sb.eh : uy >= sb.eh ? uy - sb.eh : uy;
          } else if (ux < 0 || uy < 0 || ux >= sb.ew || uy >= sb.eh) {
            return;
          }
          iweight += wk;
          const int64_t texel = static_cast<int64_t>(uy) * sb.ew + ux;
          if (first < 0) first = texel;
          same = same && texel == first;
          const unsigned char* b = bytes + static_cast<size_t>(texel) * tb;
          if (swar) {
            lanes += static_cast<uint64_t>(wk) * packed[texel];
          } else if (wide) {
            uint16_t v[3];
            std::memcpy(v, b, 6);
            s0 += wk * v[0], s1 += wk * v[1], s2 += wk * v[2];
          } else {
            s0 += wk * b[0], s1 += wk * b[1], s2 += wk * b[2];
          }
        };
        for (int ddy = -R; ddy <= R; ++ddy) {
          const int yy = y + R + ddy;
          const int64_t wy = R + 1 - std::abs(ddy);
          const int32_t* re = &run_end[static_cast<size_t>(yy - sy0) * pw];
          for (int k = 0; k <= 2 * R;) {  // padded x + k = tap dx = k - R
            const int e = std::min(re[x + k] - x, 2 * R);
            add(yy, x + k, k - R, ddy, wy * (tent[e + 1] - tent[k]));
            k = e + 1;
          }
        }
        if (same) {  // inside a patch: a verbatim copy (all of the texel's bytes)
          std::memcpy(dst, &pal.bytes[static_cast<size_t>(first) * tb], tb);
          continue;
        }
        if (swar) {
          const uint64_t mask = (uint64_t(1) << 21) - 1;
          s0 = static_cast<int64_t>(lanes & mask), s1 = static_cast<int64_t>((lanes >> 21) & mask);
          s2 = static_cast<int64_t>(lanes >> 42);
        }
        const int64_t isum[3] = {s0, s1, s2};
        for (int c = 0; c < 3; ++c) {
          const int64_t code = (2 * isum[c] + iweight) / (2 * iweight);
          if (wide) {
            const uint16_t v = static_cast<uint16_t>(code);
            std::memcpy(dst + 2 * c, &v, 2);
          } else {
            dst[c] = static_cast<unsigned char>(code);
          }
        }
        continue;
      }
      if (sb.predict(P, pw, x, y, pred.data())) {  // inside a patch: a verbatim copy
        std::memcpy(dst, &pal.bytes[static_cast<size_t>(pred[0]) * tb], tb);
        continue;
      }
      double sum[3] = {0, 0, 0}, weight = 0;
      for (size_t k = 0; k < pred.size(); ++k) {
        if (pred[k] < 0) continue;
        const double wk = sb.weight[k];
        weight += wk;
        const double* v = &term[3 * static_cast<size_t>(pred[k])];
        for (int c = 0; c < 3; ++c) sum[c] += wk * v[c];
      }
      double res[3];
      if (normal) {
        const double len = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
        for (int c = 0; c < 3; ++c) {
          const double nc = len > 0 ? sum[c] / len : (c == 2 ? 1.0 : 0.0);
          res[c] = from_unit(std::clamp((nc + 1.0) / 2.0, 0.0, 1.0));
        }
      } else {
        for (int c = 0; c < 3; ++c) res[c] = sum[c] / weight;
      }
      for (int c = 0; c < 3; ++c) {
        if (flt) {
          const float f = static_cast<float>(res[c]);
          std::memcpy(dst + 4 * c, &f, 4);
        } else if (wide) {
          const uint16_t v = static_cast<uint16_t>(std::clamp(std::lround(res[c]), 0L, 65535L));
          std::memcpy(dst + 2 * c, &v, 2);
        } else {
          dst[c] = static_cast<unsigned char>(std::clamp(std::lround(res[c]), 0L, 255L));
        }
      }
    }
  }
  };
  const int threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 8u));
  const int n = yb - ya;
  if (threads == 1 || static_cast<size_t>(w) * n < 16384) {
    blend_rows(ya, yb);
    return;
  }
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back(blend_rows, ya + n * t / threads, ya + n * (t + 1) / threads);
  for (auto& th : pool) th.join();
}

}  // namespace

void check_outputs(const RenderOutputs& o, const Exemplar& ex) {
  if (o.bits != 0 && o.bits != 8 && o.bits != 16) throw UsageError("--bits must be 8 or 16");
  if (o.colour.empty()) throw UsageError("an output file is required (-o out.png)");
  file_type(o.colour, o.bits);
  check_folder(o.colour);
  if (!o.coords.empty()) {
    if (ext_of(o.coords) != ".exr" && ext_of(o.coords) != ".tif" && ext_of(o.coords) != ".tiff")
      throw UsageError(fmt::format("--coords '{}' must be an .exr (or float .tif) file", o.coords.string()),
                       "the coordinate map holds exemplar pixel positions, e.g. --coords uv.exr");
    check_folder(o.coords);
  }
  if (!o.maps.empty() && o.maps.size() != ex.maps.size()) throw Error("internal: one output per map expected");
  for (const auto& m : o.maps) {
    file_type(m, o.bits);
    check_folder(m);
  }
}

Image colours_of(const std::vector<int32_t>& coords, int width, int height, const Image& src) {
  Image out(width, height);
  for (size_t i = 0; i < static_cast<size_t>(width) * height; ++i) {
    const float* p = src.pixel(coords[2 * i], coords[2 * i + 1]);
    std::copy(p, p + 3, out.pixels.data() + 3 * i);
  }
  return out;
}

RenderStats render(Synthesizer& synth, const Exemplar& ex, const Window& win, const SynthOptions& options,
                   const RenderOutputs& o, const std::function<void(double)>& progress, size_t max_strip_pixels) {
  check_outputs(o, ex);
  const auto start = std::chrono::steady_clock::now();
  struct Target {
    std::unique_ptr<StripFile> file;
    Palette palette;
    bool normal = false;
  };
  std::vector<Target> targets;
  auto add = [&](const fs::path& path, const Image& src, bool normal) {
    const PixelType t = file_type(path, o.bits);
    Target tg;
    tg.palette = make_palette(src, t);
    tg.normal = normal;
    tg.file = std::make_unique<StripFile>(path, win.width, win.height, t, t == PixelType::Half, o.png_compression);
    targets.push_back(std::move(tg));
  };
  add(o.colour, ex.colour, false);
  for (size_t i = 0; i < o.maps.size(); ++i) add(o.maps[i], ex.maps[i].image, ex.maps[i].kind == MapKind::Normal);
  std::unique_ptr<StripFile> coords;
  if (!o.coords.empty())
    coords = std::make_unique<StripFile>(o.coords, win.width, win.height, PixelType::Float, true);

  RenderStats stats;
  const int rows_per_strip =
      static_cast<int>(std::clamp<size_t>(max_strip_pixels / static_cast<size_t>(win.width), 1, win.height));
  std::vector<unsigned char> buffer;
  std::vector<float> coord_rows;
  std::vector<int32_t> S, P;
  const int R = o.blend_seams ? o.blend_radius : 0;
  const SeamBlend blend(std::max(R, 1), ex.width(), ex.height(), synth.analysis().toroidal);
  BlendScratch scratch;
  timing::mark("output files opened, palettes");
  for (int y0 = 0; y0 < win.height; y0 += rows_per_strip) {
    const int rows = std::min(rows_per_strip, win.height - y0);
    const size_t n = static_cast<size_t>(win.width) * rows;
    if (R > 0) {
      // R pixels more on every side (exact by spatial determinism; a tileable plane wraps by itself).
      const Window strip{win.x - R, win.y + y0 - R, win.width + 2 * R, rows + 2 * R};
      P = synth.synthesise(strip, options);
      // The blend reads P; the strip's own coordinates are needed only for --coords.
      if (coords) S.resize(2 * n);
      for (int y = 0; coords && y < rows; ++y)
        std::memcpy(&S[2 * static_cast<size_t>(y) * win.width], &P[2 * ((y + R) * static_cast<size_t>(strip.width) + R)],
                    2 * sizeof(int32_t) * win.width);
    } else {
      S = synth.synthesise(Window{win.x, win.y + y0, win.width, rows}, options);
    }
    stats.peak_strip_pixels = std::max(stats.peak_strip_pixels, n);
    timing::mark("strip copied out");
    for (auto& t : targets) {
      buffer.resize(n * t.palette.texel_bytes);
      if (R > 0) {
        // Blended in chunks of rows; each chunk is encoded and written on a second thread while the
        // next one is blended (the writes stay in order: a chunk's write starts after the previous
        // one's ended). The bytes do not depend on the chunks.
        // Chunks of a quarter strip (at least 64 rows): eighths cost ~1 ms more CPU (the summed-area
        // table's 2R extra rows per chunk, thread starts).
        const int chunk = std::max(64, (rows + 3) / 4);
        const size_t row_bytes = static_cast<size_t>(win.width) * t.palette.texel_bytes;
        std::future<void> writing;
        for (int c0 = 0; c0 < rows; c0 += chunk) {
          const int c1 = std::min(rows, c0 + chunk);
          blend_strip(t.palette, t.normal, blend, P, win.width + 2 * R, win.width, rows, buffer, c0, c1, scratch);
          if (writing.valid()) writing.get();
          writing = std::async(std::launch::async, [&t, &buffer, y0, c0, c1, row_bytes] {
            t.file->write(y0 + c0, c1 - c0, t.palette.type, buffer.data() + static_cast<size_t>(c0) * row_bytes);
          });
        }
        writing.get();
        timing::mark("seam blend + encode + write rows");
        continue;
      } else {
        for (size_t i = 0; i < n; ++i) {
          const size_t texel = static_cast<size_t>(S[2 * i + 1]) * ex.width() + S[2 * i];
          std::memcpy(&buffer[i * t.palette.texel_bytes], &t.palette.bytes[texel * t.palette.texel_bytes],
                      t.palette.texel_bytes);
        }
      }
      timing::mark(R > 0 ? "seam blend" : "colour gather");
      t.file->write(y0, rows, t.palette.type, buffer.data());
      timing::mark("encode + write rows");
    }
    if (coords) {
      coord_rows.resize(n * 3);
      for (size_t i = 0; i < n; ++i) {
        coord_rows[3 * i] = static_cast<float>(S[2 * i]);
        coord_rows[3 * i + 1] = static_cast<float>(S[2 * i + 1]);
        coord_rows[3 * i + 2] = 0.0f;
      }
      coords->write(y0, rows, PixelType::Float, coord_rows.data());
    }
    ++stats.strips;
    if (progress) progress(double(y0 + rows) / win.height);
  }
  for (auto& t : targets) t.file->close();
  if (coords) coords->close();
  for (auto& t : targets) t.file->commit();
  if (coords) coords->commit();
  timing::mark("close + rename files");
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

RenderStats write_strips(const std::vector<StripTarget>& files, int width, int height, int bits, int rows_per_strip,
                         const std::function<void(int, int, std::vector<std::vector<float>>&)>& produce,
                         const std::function<void(double)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<StripFile>> out;
  std::vector<PixelType> types;
  for (const auto& f : files) {
    const PixelType t = f.raw ? PixelType::Float : file_type(f.path, bits);
    types.push_back(t);
    out.push_back(std::make_unique<StripFile>(f.path, width, height, t, f.raw || t == PixelType::Half));
  }
  RenderStats stats;
  rows_per_strip = std::clamp(rows_per_strip, 1, height);
  std::vector<std::vector<float>> data(files.size());
  std::vector<unsigned char> bytes;
  for (int y0 = 0; y0 < height; y0 += rows_per_strip) {
    const int rows = std::min(rows_per_strip, height - y0);
    const size_t n = static_cast<size_t>(width) * rows * 3;
    for (auto& d : data) d.assign(n, 0.0f);
    produce(y0, rows, data);
    stats.peak_strip_pixels = std::max(stats.peak_strip_pixels, n / 3);
    for (size_t k = 0; k < files.size(); ++k) {
      auto& d = data[k];
      if (files[k].raw) {
        out[k]->write(y0, rows, PixelType::Float, d.data());
      } else if (types[k] == PixelType::Half) {
        for (float& v : d) v = srgb_to_linear(std::clamp(v, 0.0f, 1.0f));
        out[k]->write(y0, rows, PixelType::Float, d.data());
      } else if (types[k] == PixelType::UInt16) {
        bytes.resize(n * 2);
        for (size_t i = 0; i < n; ++i) {
          const uint16_t v = static_cast<uint16_t>(std::lround(std::clamp(d[i], 0.0f, 1.0f) * 65535.0f));
          std::memcpy(&bytes[i * 2], &v, 2);
        }
        out[k]->write(y0, rows, PixelType::UInt16, bytes.data());
      } else {
        bytes.resize(n);
        for (size_t i = 0; i < n; ++i) bytes[i] = static_cast<unsigned char>(std::lround(std::clamp(d[i], 0.0f, 1.0f) * 255.0f));
        out[k]->write(y0, rows, PixelType::UInt8, bytes.data());
      }
    }
    ++stats.strips;
    if (progress) progress(double(y0 + rows) / height);
  }
  for (auto& f : out) f->close();
  for (auto& f : out) f->commit();
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

}  // namespace proctex::synth
