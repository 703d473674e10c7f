#include "synth/render.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include "core/error.h"

namespace proctex::synth {
namespace fs = std::filesystem;
namespace {

std::string ext_of(const fs::path& p) {
  std::string e = p.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// The pixel type written for a file: PNG 8/16, JPEG 8, TIFF 8/16, EXR half (colour) or float (coords).
OIIO::TypeDesc file_type(const fs::path& p, int bits) {
  const std::string e = ext_of(p);
  if (e == ".exr") return OIIO::TypeDesc::HALF;
  if (e == ".jpg" || e == ".jpeg") return OIIO::TypeDesc::UINT8;
  if (e == ".png") return bits == 16 ? OIIO::TypeDesc::UINT16 : OIIO::TypeDesc::UINT8;
  if (e == ".tif" || e == ".tiff") return bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
  throw UsageError(fmt::format("cannot write '{}': unknown extension", p.string()), "use .png, .tif, .exr or .jpg");
}

// Every texel of the source encoded once in the file's pixel type: a strip is then a gather.
struct Palette {
  OIIO::TypeDesc type;
  size_t texel_bytes = 0;
  std::vector<unsigned char> bytes;
};

Palette make_palette(const Image& src, OIIO::TypeDesc type) {
  Palette p;
  const size_t n = static_cast<size_t>(src.width) * src.height;
  if (type == OIIO::TypeDesc::HALF) {
    p.type = OIIO::TypeDesc::FLOAT;  // OIIO converts float to half when writing
    p.texel_bytes = 3 * sizeof(float);
    p.bytes.resize(n * p.texel_bytes);
    std::memcpy(p.bytes.data(), src.pixels.data(), p.bytes.size());
    return p;
  }
  const bool wide = type == OIIO::TypeDesc::UINT16;
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
  return p;
}

fs::path temporary_beside(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  for (int attempt = 0;; ++attempt) {
    const fs::path temp = dir / ("." + target.stem().string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                                 std::to_string(counter++) + target.extension().string());
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return temp;
    }
    if (errno != EEXIST || attempt > 100) {
      throw Error(fmt::format("cannot write '{}': {}", target.string(), std::strerror(errno)),
                  "check that the folder is writable and the disk is not full");
    }
  }
}

// One output file written strip by strip into a temporary; commit() renames it into place, the
// destructor removes an uncommitted temporary.
class StripFile {
 public:
  StripFile(fs::path target, int width, int height, OIIO::TypeDesc file_format, bool linear)
      : target_(std::move(target)), temp_(temporary_beside(target_)) {
    out_ = OIIO::ImageOutput::create(temp_.string());
    OIIO::ImageSpec spec(width, height, 3, file_format);
    spec.attribute("oiio:ColorSpace", linear ? "Linear" : "sRGB");
    if (ext_of(target_) == ".png") spec.attribute("png:compressionLevel", 1);
    if (!out_ || !out_->open(temp_.string(), spec)) fail();
  }
  ~StripFile() {
    if (!committed_) {
      if (out_) out_->close();
      std::error_code ec;
      fs::remove(temp_, ec);
    }
  }
  void write(int y0, int rows, OIIO::TypeDesc type, const void* data) {
    if (!out_->write_scanlines(y0, y0 + rows, 0, type, data)) fail();
  }
  void close() {
    if (!out_->close()) fail();
  }
  void commit() {
    std::error_code ec;
    fs::rename(temp_, target_, ec);
    if (ec) throw Error(fmt::format("cannot write '{}': {}", target_.string(), ec.message()), "check the folder");
    committed_ = true;
  }

 private:
  [[noreturn]] void fail() {
    std::string msg = out_ ? out_->geterror() : OIIO::geterror();
    if (msg.empty()) msg = "the image writer failed";
    throw Error(fmt::format("cannot write '{}': {}", target_.string(), msg),
                "check that the folder is writable and the disk is not full");
  }
  fs::path target_, temp_;
  std::unique_ptr<OIIO::ImageOutput> out_;
  bool committed_ = false;
};

void check_folder(const fs::path& p) {
  const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error(fmt::format("cannot write '{}': folder '{}' does not exist", p.string(), dir.string()),
                "create the folder first or choose another output path");
  }
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
  };
  std::vector<Target> targets;
  auto add = [&](const fs::path& path, const Image& src) {
    const OIIO::TypeDesc t = file_type(path, o.bits);
    Target tg;
    tg.palette = make_palette(src, t);
    tg.file = std::make_unique<StripFile>(path, win.width, win.height, t, t == OIIO::TypeDesc::HALF);
    targets.push_back(std::move(tg));
  };
  add(o.colour, ex.colour);
  for (size_t i = 0; i < o.maps.size(); ++i) add(o.maps[i], ex.maps[i].image);
  std::unique_ptr<StripFile> coords;
  if (!o.coords.empty())
    coords = std::make_unique<StripFile>(o.coords, win.width, win.height, OIIO::TypeDesc::FLOAT, true);

  RenderStats stats;
  const int rows_per_strip =
      static_cast<int>(std::clamp<size_t>(max_strip_pixels / static_cast<size_t>(win.width), 1, win.height));
  std::vector<unsigned char> buffer;
  std::vector<float> coord_rows;
  for (int y0 = 0; y0 < win.height; y0 += rows_per_strip) {
    const int rows = std::min(rows_per_strip, win.height - y0);
    const Window strip{win.x, win.y + y0, win.width, rows};
    const std::vector<int32_t> S = synth.synthesise(strip, options);
    const size_t n = static_cast<size_t>(win.width) * rows;
    stats.peak_strip_pixels = std::max(stats.peak_strip_pixels, n);
    for (auto& t : targets) {
      buffer.resize(n * t.palette.texel_bytes);
      for (size_t i = 0; i < n; ++i) {
        const size_t texel = static_cast<size_t>(S[2 * i + 1]) * ex.width() + S[2 * i];
        std::memcpy(&buffer[i * t.palette.texel_bytes], &t.palette.bytes[texel * t.palette.texel_bytes],
                    t.palette.texel_bytes);
      }
      t.file->write(y0, rows, t.palette.type, buffer.data());
    }
    if (coords) {
      coord_rows.resize(n * 3);
      for (size_t i = 0; i < n; ++i) {
        coord_rows[3 * i] = static_cast<float>(S[2 * i]);
        coord_rows[3 * i + 1] = static_cast<float>(S[2 * i + 1]);
        coord_rows[3 * i + 2] = 0.0f;
      }
      coords->write(y0, rows, OIIO::TypeDesc::FLOAT, coord_rows.data());
    }
    ++stats.strips;
    if (progress) progress(double(y0 + rows) / win.height);
  }
  for (auto& t : targets) t.file->close();
  if (coords) coords->close();
  for (auto& t : targets) t.file->commit();
  if (coords) coords->commit();
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return stats;
}

RenderStats write_strips(const std::vector<StripTarget>& files, int width, int height, int bits, int rows_per_strip,
                         const std::function<void(int, int, std::vector<std::vector<float>>&)>& produce,
                         const std::function<void(double)>& progress) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::unique_ptr<StripFile>> out;
  std::vector<OIIO::TypeDesc> types;
  for (const auto& f : files) {
    const OIIO::TypeDesc t = f.raw ? OIIO::TypeDesc::FLOAT : file_type(f.path, bits);
    types.push_back(t);
    out.push_back(std::make_unique<StripFile>(f.path, width, height, t, f.raw || t == OIIO::TypeDesc::HALF));
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
        out[k]->write(y0, rows, OIIO::TypeDesc::FLOAT, d.data());
      } else if (types[k] == OIIO::TypeDesc::HALF) {
        for (float& v : d) v = srgb_to_linear(std::clamp(v, 0.0f, 1.0f));
        out[k]->write(y0, rows, OIIO::TypeDesc::FLOAT, d.data());
      } else if (types[k] == OIIO::TypeDesc::UINT16) {
        bytes.resize(n * 2);
        for (size_t i = 0; i < n; ++i) {
          const uint16_t v = static_cast<uint16_t>(std::lround(std::clamp(d[i], 0.0f, 1.0f) * 65535.0f));
          std::memcpy(&bytes[i * 2], &v, 2);
        }
        out[k]->write(y0, rows, OIIO::TypeDesc::UINT16, bytes.data());
      } else {
        bytes.resize(n);
        for (size_t i = 0; i < n; ++i) bytes[i] = static_cast<unsigned char>(std::lround(std::clamp(d[i], 0.0f, 1.0f) * 255.0f));
        out[k]->write(y0, rows, OIIO::TypeDesc::UINT8, bytes.data());
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
