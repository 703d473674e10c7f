// RGBN type, files, normal maps, height fields.
#include "rgbn/rgbn.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <unistd.h>

#include "core/error.h"
#include "image/io.h"
#include "metrics/fft.h"

namespace proctex::rgbn {
namespace fs = std::filesystem;

Rgbn::Rgbn(int w, int h, float grey) : width(w), height(h) {
  check_dimensions(w, h);
  albedo.assign(size() * 3, grey);
  normal.assign(size() * 3, 0.0f);
  for (size_t i = 0; i < size(); ++i) normal[3 * i + 2] = 1.0f;
}

void normalize_normals(Rgbn& image) {
  for (size_t i = 0; i < image.size(); ++i) {
    float* n = &image.normal[3 * i];
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 1e-12f) || !std::isfinite(len)) {
      n[0] = n[1] = 0.0f;
      n[2] = 1.0f;
    } else {
      n[0] /= len, n[1] /= len, n[2] /= len;
    }
  }
}

double max_norm_error(const Rgbn& image) {
  double worst = 0;
  for (size_t i = 0; i < image.size(); ++i) {
    const float* n = &image.normal[3 * i];
    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    worst = std::max(worst, std::isfinite(len) ? std::abs(len - 1.0) : 1e30);
  }
  return worst;
}

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

std::string lower_ext(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

using RawImage = ChannelImage;  // integer formats scaled to [0, 1]

RawImage read_raw(const fs::path& path) {
  if (!fs::exists(path)) throw Error("cannot read " + quoted(path) + ": no such file", "check the path");
  return read_channels(path);
}

// Writes through a temporary and a rename (image/io.h).
void write_atomic(const fs::path& path, int w, int h, const WriteOptions& options, PixelType data_type,
                  const void* data) {
  write_channels(path, w, h, options, data_type, data);
}

WriteOptions file_options(int channels, PixelType type, const std::string& compression = "") {
  WriteOptions o;
  o.channels = channels;
  o.file_type = type;
  o.compression = compression;
  return o;
}

int find_channel(const RawImage& r, const std::string& name) {
  for (int c = 0; c < r.channels; ++c)
    if (r.channel_names.size() > size_t(c) && r.channel_names[c] == name) return c;
  return -1;
}

}  // namespace

Rgbn load_rgbn(const fs::path& path, double tolerance) {
  const RawImage r = read_raw(path);
  const char* names[6] = {"R", "G", "B", "N.X", "N.Y", "N.Z"};
  int idx[6];
  for (int k = 0; k < 6; ++k) {
    idx[k] = find_channel(r, names[k]);
    if (idx[k] < 0)
      throw Error("RGBN file " + quoted(path) + " has no channel " + names[k],
                  "an RGBN is an EXR with channels R,G,B,N.X,N.Y,N.Z; import a normal map with 'proctex rgbn import'");
  }
  Rgbn out;
  out.width = r.width, out.height = r.height;
  out.albedo.resize(out.size() * 3);
  out.normal.resize(out.size() * 3);
  for (size_t i = 0; i < out.size(); ++i) {
    const float* px = &r.data[i * r.channels];
    for (int c = 0; c < 3; ++c) out.albedo[3 * i + c] = px[idx[c]];
    float* n = &out.normal[3 * i];
    for (int c = 0; c < 3; ++c) n[c] = px[idx[3 + c]];
    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (!std::isfinite(len) || std::abs(len - 1.0) > tolerance) {
      throw Error("RGBN file " + quoted(path) + " has a " + (std::isfinite(len) ? "non-unit" : "non-finite") +
                      " normal at pixel (" + std::to_string(i % out.width) + ", " + std::to_string(i / out.width) +
                      "), length " + std::to_string(len),
                  "normals must be unit vectors; re-import the normal map with 'proctex rgbn import'");
    }
    for (int c = 0; c < 3; ++c) n[c] = float(n[c] / len);
  }
  return out;
}

void save_rgbn(const Rgbn& image, const fs::path& path) {
  if (image.empty() || image.albedo.size() != image.size() * 3 || image.normal.size() != image.size() * 3)
    throw Error("cannot save RGBN " + quoted(path) + ": the image is empty or inconsistent", "this is a bug");
  if (lower_ext(path) != ".exr")
    throw UsageError("an RGBN file must be an .exr: " + quoted(path), "use 'proctex rgbn export' for PNG/TIFF normal maps");
  WriteOptions spec = file_options(6, PixelType::Float, "zip");
  spec.channel_names = {"R", "G", "B", "N.X", "N.Y", "N.Z"};
  spec.attributes = {{"proctex:content", "rgbn"}};
  std::vector<float> data(image.size() * 6);
  for (size_t i = 0; i < image.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      data[6 * i + c] = image.albedo[3 * i + c];
      data[6 * i + 3 + c] = image.normal[3 * i + c];
    }
  write_atomic(path, image.width, image.height, spec, PixelType::Float, data.data());
}

Convention parse_convention(const std::string& name) {
  std::string s = name;
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  if (s == "gl" || s == "opengl") return Convention::OpenGL;
  if (s == "dx" || s == "directx") return Convention::DirectX;
  throw UsageError("unknown normal-map convention '" + name + "'",
                   "use --convention gl (OpenGL, +Y up: Blender, Maya, Substance 'OpenGL') or dx (DirectX, +Y down: Unreal, 3ds Max)");
}

std::string convention_name(Convention c) { return c == Convention::OpenGL ? "gl" : "dx"; }

void save_normal_map(const Rgbn& image, const fs::path& path, Convention convention, int bits) {
  if (image.empty()) throw Error("cannot save an empty normal map", "this is a bug");
  const std::string ext = lower_ext(path);
  const float ysign = convention == Convention::DirectX ? -1.0f : 1.0f;
  if (ext == ".exr") {
    const WriteOptions spec = file_options(3, PixelType::Float, "zip");
    std::vector<float> data(image.normal);
    for (size_t i = 0; i < image.size(); ++i) data[3 * i + 1] *= ysign;
    write_atomic(path, image.width, image.height, spec, PixelType::Float, data.data());
    return;
  }
  if (ext != ".png" && ext != ".tif" && ext != ".tiff")
    throw UsageError("cannot write a normal map as '" + path.extension().string() + "'", "use .png, .tif or .exr");
  if (bits != 8 && bits != 16) throw UsageError("--bits must be 8 or 16, not " + std::to_string(bits), "use 8 or 16");
  const double scale = bits == 8 ? 127.5 : 32767.5;
  const double top = bits == 8 ? 255.0 : 65535.0;
  auto encode = [&](float x) { return std::clamp(std::round((double(x) + 1.0) * scale), 0.0, top); };
  if (bits == 8) {
    const WriteOptions spec = file_options(3, PixelType::UInt8);
    std::vector<uint8_t> data(image.size() * 3);
    for (size_t i = 0; i < image.size(); ++i)
      for (int c = 0; c < 3; ++c) data[3 * i + c] = uint8_t(encode(image.normal[3 * i + c] * (c == 1 ? ysign : 1.0f)));
    write_atomic(path, image.width, image.height, spec, PixelType::UInt8, data.data());
  } else {
    const WriteOptions spec = file_options(3, PixelType::UInt16);
    std::vector<uint16_t> data(image.size() * 3);
    for (size_t i = 0; i < image.size(); ++i)
      for (int c = 0; c < 3; ++c) data[3 * i + c] = uint16_t(encode(image.normal[3 * i + c] * (c == 1 ? ysign : 1.0f)));
    write_atomic(path, image.width, image.height, spec, PixelType::UInt16, data.data());
  }
}

Rgbn load_normal_map(const fs::path& path, Convention convention, const Image* albedo) {
  const RawImage r = read_raw(path);
  if (r.channels < 3)
    throw Error("normal map " + quoted(path) + " has " + std::to_string(r.channels) + " channel(s), not 3",
                "a normal map stores X, Y, Z in red, green, blue");
  const bool is_float = r.file_type == PixelType::Float || r.file_type == PixelType::Half;
  const float ysign = convention == Convention::DirectX ? -1.0f : 1.0f;
  Rgbn out(r.width, r.height);
  for (size_t i = 0; i < out.size(); ++i) {
    float* n = &out.normal[3 * i];
    for (int c = 0; c < 3; ++c) {
      const float v = r.data[i * r.channels + c];
      n[c] = is_float ? v : v * 2.0f - 1.0f;
    }
    n[1] *= ysign;
    const float len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!std::isfinite(len) || len < 0.5f)
      throw Error("normal map " + quoted(path) + " has a " + (std::isfinite(len) ? "zero-length" : "non-finite") +
                      " normal at pixel (" + std::to_string(i % out.width) + ", " + std::to_string(i / out.width) + ")",
                  "is it a normal map (bluish, (128,128,255) where flat)? a height map imports with --height");
    for (int c = 0; c < 3; ++c) n[c] /= len;
  }
  if (albedo) set_albedo(out, *albedo);
  return out;
}

void set_albedo(Rgbn& image, const Image& albedo) {
  if (albedo.width != image.width || albedo.height != image.height)
    throw Error("the albedo image is " + std::to_string(albedo.width) + "x" + std::to_string(albedo.height) +
                    " but the normals are " + std::to_string(image.width) + "x" + std::to_string(image.height),
                "give images of the same size");
  image.albedo = albedo.pixels;
}

Image albedo_image(const Rgbn& image) {
  Image out(image.width, image.height);
  out.pixels = image.albedo;
  return out;
}

Rgbn from_height(const HeightField& z, float scale, bool wrap) {
  if (z.width < 2 || z.height < 2 || z.z.size() != size_t(z.width) * z.height)
    throw Error("a height field must be at least 2x2", "give a larger height map");
  Rgbn out(z.width, z.height);
  const int w = z.width, h = z.height;
  for (int y = 0; y < h; ++y) {
    // y is up: the row above (y - 1) is +y.
    int up = y - 1, down = y + 1;
    float dy = 2.0f;
    if (wrap) {
      up = (up + h) % h, down = down % h;
    } else if (up < 0) {
      up = y, dy = 1.0f;
    } else if (down >= h) {
      down = y, dy = 1.0f;
    }
    for (int x = 0; x < w; ++x) {
      int l = x - 1, r = x + 1;
      float dx = 2.0f;
      if (wrap) {
        l = (l + w) % w, r = r % w;
      } else if (l < 0) {
        l = x, dx = 1.0f;
      } else if (r >= w) {
        r = x, dx = 1.0f;
      }
      const float p = scale * (z.at(r, y) - z.at(l, y)) / dx;
      const float q = scale * (z.at(x, up) - z.at(x, down)) / dy;
      const float inv = 1.0f / std::sqrt(p * p + q * q + 1.0f);
      float* n = out.n(x, y);
      n[0] = -p * inv, n[1] = -q * inv, n[2] = inv;
    }
  }
  return out;
}

HeightField height_from_image(const Image& image) {
  HeightField hf{image.width, image.height, luminance(image)};
  const auto [lo, hi] = std::minmax_element(hf.z.begin(), hf.z.end());
  const float l = *lo, range = std::max(*hi - *lo, 1e-12f);
  for (float& v : hf.z) v = (v - l) / range;
  return hf;
}

void slopes(const Rgbn& image, std::vector<float>& p, std::vector<float>& q, float min_nz) {
  p.resize(image.size());
  q.resize(image.size());
  for (size_t i = 0; i < image.size(); ++i) {
    const float* n = &image.normal[3 * i];
    const float nz = std::max(n[2], min_nz);
    p[i] = -n[0] / nz;
    q[i] = -n[1] / nz;
  }
}

void set_slopes(Rgbn& image, const std::vector<float>& p, const std::vector<float>& q) {
  for (size_t i = 0; i < image.size(); ++i) {
    const float inv = 1.0f / std::sqrt(p[i] * p[i] + q[i] * q[i] + 1.0f);
    float* n = &image.normal[3 * i];
    n[0] = -p[i] * inv, n[1] = -q[i] * inv, n[2] = inv;
  }
}

double integrability_error(const Rgbn& image, const std::vector<float>* mask) {
  std::vector<float> p, q;
  slopes(image, p, q);
  const int w = image.width, h = image.height;
  double sum = 0;
  size_t count = 0;
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (mask && (*mask)[i] == 0.0f) continue;
      const float dq_dx = (q[i + 1] - q[i - 1]) * 0.5f;
      const float dp_dy = (p[i - w] - p[i + w]) * 0.5f;  // y up
      sum += std::abs(dq_dx - dp_dy);
      ++count;
    }
  return count ? sum / double(count) : 0.0;
}

Integration to_height(const Rgbn& image, bool periodic) {
  using namespace metrics::detail;
  std::vector<float> p, q;
  slopes(image, p, q);
  const int w = image.width, h = image.height;
  // Mirror (even extension) for non-periodic fields: p is odd in x, even in y; q the reverse.
  const int W = periodic ? w : 2 * w, H = periodic ? h : 2 * h;
  FftwArray<float> rp(size_t(W) * H), rq(size_t(W) * H);
  for (int Y = 0; Y < H; ++Y)
    for (int X = 0; X < W; ++X) {
      const bool mx = X >= w, my = Y >= h;
      const int x = mx ? 2 * w - 1 - X : X, y = my ? 2 * h - 1 - Y : Y;
      const size_t i = size_t(y) * w + x;
      rp[size_t(Y) * W + X] = mx ? -p[i] : p[i];
      rq[size_t(Y) * W + X] = my ? -q[i] : q[i];
    }
  const int C = W / 2 + 1;
  FftwArray<Complex> fp(size_t(H) * C), fq(size_t(H) * C);
  fft_r2c(H, W, rp, fp);
  fft_r2c(H, W, rq, fq);
  // z_x = p, z_y(up) = q = -z_row. The slopes are central differences, whose frequency response
  // is i sin(w): minimise |i sx Z - P|^2 + |i sy Z + Q|^2 => Z = (-i sx P + i sy Q) / (sx^2 + sy^2).
  // (Frankot-Chellappa with the discrete derivative, so the normals of a height field give it back.)
  const double two_pi = 2.0 * M_PI;
  // Near the Nyquist frequency sin(w) -> 0 and 1/sin would amplify noise into row/column stripes:
  // the denominator is floored at (w/2)^2 there (below w ~ 1.9 it is the exact sin^2).
  for (int ky = 0; ky < H; ++ky) {
    const double fy = two_pi * (ky <= H / 2 ? ky : ky - H) / H;
    const double wy = std::sin(fy);
    for (int kx = 0; kx < C; ++kx) {
      const double fx = two_pi * kx / W;
      const double wx = std::sin(fx);
      const size_t i = size_t(ky) * C + kx;
      const double d = std::max(wx * wx + wy * wy, 0.25 * (fx * fx + fy * fy));
      if (fx == 0 && fy == 0) {
        fp[i] = 0;
        continue;
      }
      const std::complex<double> P(fp[i].real(), fp[i].imag()), Q(fq[i].real(), fq[i].imag());
      const std::complex<double> I(0, 1);
      const std::complex<double> Z = (-I * wx * P + I * wy * Q) / d;
      fp[i] = Complex(float(Z.real()), float(Z.imag()));
    }
  }
  FftwArray<float> zr(size_t(W) * H);
  fft_c2r(H, W, fp, zr);
  Integration out;
  out.z = HeightField{w, h, std::vector<float>(size_t(w) * h)};
  double mean = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) mean += (out.z.at(x, y) = zr[size_t(y) * W + x] / float(W * H));
  mean /= double(w) * h;
  for (float& v : out.z.z) v = float(v - mean);
  out.integrability = integrability_error(image);
  // Residual: forward differences of z against the slopes averaged to the same half-pixel place.
  double sq = 0;
  size_t count = 0;
  for (int y = 0; y + 1 < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const double zx = out.z.at(x + 1, y) - out.z.at(x, y);
      const double zy = out.z.at(x, y) - out.z.at(x, y + 1);
      const double px = 0.5 * (p[i] + p[i + 1]), qy = 0.5 * (q[i] + q[i + w]);
      sq += (zx - px) * (zx - px) + (zy - qy) * (zy - qy);
      count += 2;
    }
  out.residual = count ? std::sqrt(sq / double(count)) : 0.0;
  return out;
}

}  // namespace proctex::rgbn

namespace proctex::rgbn::detail {

void write_exr(const fs::path& path, int w, int h, const std::vector<std::string>& channels,
               const std::vector<float>& data) {
  if (lower_ext(path) != ".exr") throw UsageError("this file must be an .exr: " + quoted(path), "use the .exr extension");
  WriteOptions spec = file_options(int(channels.size()), PixelType::Float, "zip");
  spec.channel_names = channels;
  write_atomic(path, w, h, spec, PixelType::Float, data.data());
}

std::vector<float> read_exr(const fs::path& path, const std::vector<std::string>& channels, int& w, int& h) {
  const RawImage r = read_raw(path);
  std::vector<int> idx;
  for (const auto& c : channels) {
    const int i = find_channel(r, c);
    if (i < 0) throw Error("file " + quoted(path) + " has no channel " + c, "was it written by proctex rgbn?");
    idx.push_back(i);
  }
  w = r.width, h = r.height;
  std::vector<float> out(size_t(w) * h * channels.size());
  for (size_t p = 0; p < size_t(w) * h; ++p)
    for (size_t c = 0; c < channels.size(); ++c) {
      const float v = r.data[p * r.channels + idx[c]];
      if (!std::isfinite(v)) throw Error("file " + quoted(path) + " holds a non-finite value", "the file is damaged");
      out[p * channels.size() + c] = v;
    }
  return out;
}

}  // namespace proctex::rgbn::detail
