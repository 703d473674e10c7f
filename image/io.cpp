// image/io.h: multi-channel files, strip writers, PNG in memory, GIF. PNG through libpng here;
// everything else through the OpenImageIO module (image/backend.h), loaded on first use.
#include "image/io.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "core/error.h"
#include "image/backend.h"
#include "image/io_internal.h"
#include "image/jpeg_codec.h"
#include "image/png_codec.h"

namespace proctex {
namespace fs = std::filesystem;

namespace detail {

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

Format sniff(const fs::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return Format::Other;
  std::array<unsigned char, 8> head{};
  const size_t n = std::fread(head.data(), 1, head.size(), f);
  std::fclose(f);
  if (png::has_signature(std::span<const unsigned char>(head.data(), n))) return Format::Png;
  if (jpeg::has_signature(head.data(), n)) return Format::Jpeg;
  return Format::Other;
}

void check_parent_directory(const fs::path& path) {
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error("cannot save image " + quoted(path) + ": directory " + quoted(dir) + " does not exist",
                "create the directory first or choose another output path");
  }
}

// Creates an empty, uniquely named file beside the target (same filesystem, so rename is atomic)
// that keeps the extension, because OpenImageIO picks the format from it. Creating it ourselves
// gives the real reason (permission denied, read-only file system) when the directory is unwritable.
fs::path create_temporary(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  for (int attempt = 0;; ++attempt) {
    const fs::path temp = dir / ("." + target.stem().string() + ".tmp-" + std::to_string(getpid()) + "-" +
                                 std::to_string(counter++) + target.extension().string());
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return temp;
    }
    if (errno != EEXIST || attempt > 100) {
      throw Error("cannot save image " + quoted(target) + ": cannot create a file in " + quoted(dir) + ": " +
                      std::strerror(errno),
                  "check that the directory is writable and the disk is not full");
    }
  }
}

}  // namespace detail

namespace {
using detail::quoted;

std::vector<std::string> default_names(int channels) {
  switch (channels) {
    case 1: return {"Y"};
    case 2: return {"Y", "A"};
    case 3: return {"R", "G", "B"};
    case 4: return {"R", "G", "B", "A"};
  }
  std::vector<std::string> names;
  for (int c = 0; c < channels; ++c) names.push_back("channel" + std::to_string(c));
  return names;
}

const char* kWriteHint = "check that the directory is writable and the disk is not full";

// Reads a PNG (file or memory) into float codes / (2^bits - 1).
ChannelImage read_png(const png::Source& source, const std::string& what, const ImageLimits& limits) {
  ChannelImage out;
  const std::string problem = png::decode(
      source,
      [&](const png::Header& h) {
        check_dimensions(h.width, h.height, limits);
        out.width = h.width, out.height = h.height, out.channels = h.channels;
        out.file_type = h.bit_depth == 16 ? PixelType::UInt16 : PixelType::UInt8;
        out.channel_names = default_names(h.channels);
        out.data.resize(size_t(h.width) * h.height * h.channels);
      },
      [&](int y0, int rows, const unsigned char* data) {
        const size_t n = size_t(rows) * out.width * out.channels;
        float* dst = out.data.data() + size_t(y0) * out.width * out.channels;
        if (out.file_type == PixelType::UInt16) {
          const auto* words = reinterpret_cast<const uint16_t*>(data);
          for (size_t i = 0; i < n; ++i) dst[i] = float(words[i]) * (1.0f / 65535.0f);  // as OpenImageIO
        } else {
          for (size_t i = 0; i < n; ++i) dst[i] = float(data[i]) * (1.0f / 255.0f);
        }
      });
  if (!problem.empty()) throw Error(what + ": " + problem, "check that the file is a complete PNG image");
  return out;
}

// Reads a JPEG into float codes / 255; empty for colour spaces left to OpenImageIO (CMYK).
ChannelImage read_jpeg(std::FILE* file, const std::string& what, const ImageLimits& limits) {
  ChannelImage out;
  const std::string problem = jpeg::decode(
      file,
      [&](const jpeg::Header& h) {
        check_dimensions(h.width, h.height, limits);
        out.width = h.width, out.height = h.height, out.channels = h.channels;
        out.channel_names = default_names(h.channels);
        out.data.resize(size_t(h.width) * h.height * h.channels);
      },
      [&](int y0, int rows, const unsigned char* data) {
        const size_t n = size_t(rows) * out.width * out.channels;
        float* dst = out.data.data() + size_t(y0) * out.width * out.channels;
        for (size_t i = 0; i < n; ++i) dst[i] = float(data[i]) * (1.0f / 255.0f);
      });
  if (problem == jpeg::kUnsupported) return {};
  if (!problem.empty()) throw Error(what + ": " + problem, "check that the file is a complete JPEG image");
  return out;
}

// The raw bytes a PNG encoder needs: `data` as is when it already has the file's type, else
// float values in [0, 1] scaled to codes.
const void* as_png_codes(PixelType file_type, PixelType data_type, const void* data, size_t count,
                         std::vector<unsigned char>& scratch) {
  if (data_type == file_type) return data;
  if (data_type != PixelType::Float) {
    throw Error("cannot convert pixel types for a PNG", "this is a bug: pass 8/16-bit codes or floats");
  }
  const auto* f = static_cast<const float*>(data);
  if (file_type == PixelType::UInt16) {
    scratch.resize(count * 2);
    auto* w = reinterpret_cast<uint16_t*>(scratch.data());
    for (size_t i = 0; i < count; ++i) w[i] = uint16_t(std::lround(std::clamp(f[i], 0.0f, 1.0f) * 65535.0f));
  } else {
    scratch.resize(count);
    for (size_t i = 0; i < count; ++i) scratch[i] = uint8_t(std::lround(std::clamp(f[i], 0.0f, 1.0f) * 255.0f));
  }
  return scratch.data();
}

}  // namespace

ChannelImage read_channels(const fs::path& path, const ImageLimits& limits) {
  const std::string what = "cannot load image " + quoted(path);
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw Error(what + ": " + (fs::exists(path, ec) ? "not a regular file" : "file not found"), "check the path");
  }
  if (fs::file_size(path, ec) == 0 && !ec) throw Error(what + ": the file is empty", "check the path");
  const detail::Format format = detail::sniff(path);
  if (format == detail::Format::Png || format == detail::Format::Jpeg) {
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw Error(what + ": " + std::strerror(errno), "check the file's permissions");
    try {
      if (format == detail::Format::Png) {
        png::Source source;
        source.file = f;
        ChannelImage out = read_png(source, what, limits);
        std::fclose(f);
        return out;
      }
      ChannelImage out = read_jpeg(f, what, limits);
      std::fclose(f);
      if (!out.data.empty()) return out;
    } catch (...) {
      std::fclose(f);
      throw;
    }
  }
  const char* hint = "check that the file is a complete PNG, JPEG, TIFF or EXR image";
  std::string error;
  auto reader = backend::get(what).open_reader(path.string(), true, error);
  if (!reader) throw Error(what + ": " + error, hint);
  const backend::Header& h = reader->header();
  try {
    check_dimensions(h.width, h.height, limits);
  } catch (const Error& e) {
    throw Error(what + ": " + e.message(), e.hint());
  }
  if (h.depth > 1 || h.channels < 1) {
    throw Error(what + ": unsupported layout (" + std::to_string(h.channels) + " channels, depth " +
                    std::to_string(h.depth) + ")",
                hint);
  }
  ChannelImage out;
  out.width = h.width, out.height = h.height, out.channels = h.channels;
  out.channel_names = h.channel_names;
  out.file_type = h.type;
  out.data.resize(size_t(h.width) * h.height * h.channels);
  if (!reader->read(h.channels, out.data.data(), std::ptrdiff_t(sizeof(float)) * h.channels, error)) {
    throw Error(what + ": " + error, hint);
  }
  return out;
}

ChannelImage decode_png(std::span<const unsigned char> bytes, const ImageLimits& limits) {
  png::Source source;
  source.memory = bytes;
  if (!png::has_signature(bytes)) {
    throw Error("cannot decode an in-memory PNG: no PNG signature", "the data is not a PNG image");
  }
  return read_png(source, "cannot decode an in-memory PNG", limits);
}

std::vector<unsigned char> encode_png(int width, int height, int channels, std::span<const uint8_t> codes,
                                      int compression_level) {
  check_dimensions(width, height);
  if (channels < 1 || channels > 4 || codes.size() != size_t(width) * height * channels) {
    throw Error("cannot encode a PNG: " + std::to_string(codes.size()) + " bytes for " + std::to_string(width) +
                    "x" + std::to_string(height) + "x" + std::to_string(channels),
                "this is a bug in the caller");
  }
  std::vector<unsigned char> out;
  png::Header h{width, height, channels, 8};
  png::Encoder encoder(nullptr, &out, h, compression_level, false);
  std::string error = encoder.write_rows(height, codes.data());
  if (error.empty()) error = encoder.finish();
  if (!error.empty()) throw Error("cannot encode a PNG: " + error, "out of memory?");
  return out;
}

// --- StripWriter

struct StripWriter::Impl {
  fs::path target, temp;
  int width = 0, height = 0;
  WriteOptions options;
  std::FILE* file = nullptr;                  // PNG
  std::unique_ptr<png::Encoder> encoder;      // PNG
  std::unique_ptr<backend::Writer> writer;    // everything else
  std::vector<unsigned char> scratch;
  bool closed = false, finished = false;

  [[noreturn]] void fail(const std::string& reason) {
    throw Error("cannot save image " + quoted(target) + ": " + (reason.empty() ? "the image writer failed" : reason),
                kWriteHint);
  }
  void discard() {
    encoder.reset();
    writer.reset();
    if (file) std::fclose(file);
    file = nullptr;
    std::error_code ec;
    fs::remove(temp, ec);
  }
};

StripWriter::StripWriter(const fs::path& path, int width, int height, const WriteOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.target = path, s.width = width, s.height = height, s.options = options;
  check_dimensions(width, height);
  const std::string ext = detail::lower_extension(path);
  const bool png = ext == ".png";
  if (!png && ext != ".exr" && ext != ".tif" && ext != ".tiff" && ext != ".jpg" && ext != ".jpeg") {
    throw Error("cannot save image " + quoted(path) + ": unknown extension '" + path.extension().string() + "'",
                "use .png, .jpg, .tif or .exr");
  }
  if (png && ((options.file_type != PixelType::UInt8 && options.file_type != PixelType::UInt16) ||
              options.channels < 1 || options.channels > 4)) {
    throw Error("cannot save image " + quoted(path) + ": PNG stores 1-4 channels of 8 or 16 bits",
                "use .exr or .tif for float data or more channels");
  }
  detail::check_parent_directory(path);
  s.temp = detail::create_temporary(path);
  if (png) {
    s.file = std::fopen(s.temp.c_str(), "wb");
    if (!s.file) {
      const std::string why = std::strerror(errno);
      s.discard();
      s.fail(why);
    }
    png::Header h{width, height, options.channels, options.file_type == PixelType::UInt16 ? 16 : 8};
    s.encoder = std::make_unique<png::Encoder>(s.file, nullptr, h, options.png_compression_level,
                                               options.colour_space == "sRGB", options.png_filter);
  } else {
    std::string error;
    try {
      s.writer = backend::get("cannot save image " + quoted(path))
                     .open_writer(s.temp.string(), width, height, options, error);
    } catch (...) {
      s.discard();
      throw;
    }
    if (!s.writer) {
      s.discard();
      s.fail(error);
    }
  }
}

StripWriter::~StripWriter() {
  if (impl_ && !impl_->finished) impl_->discard();
}

void StripWriter::write_rows(int y0, int rows, PixelType data_type, const void* data) {
  Impl& s = *impl_;
  if (s.encoder) {
    const void* codes = as_png_codes(s.options.file_type, data_type, data,
                                     size_t(s.width) * rows * s.options.channels, s.scratch);
    if (const std::string e = s.encoder->write_rows(rows, codes); !e.empty()) s.fail(e);
  } else {
    std::string error;
    if (!s.writer->write_rows(y0, y0 + rows, data_type, data, error)) s.fail(error);
  }
}

void StripWriter::close() {
  Impl& s = *impl_;
  if (s.closed) return;
  s.closed = true;
  std::string error;
  if (s.encoder) {
    error = s.encoder->finish();
    s.encoder.reset();
    if (std::fclose(s.file) != 0 && error.empty()) error = std::strerror(errno);
    s.file = nullptr;
  } else if (!s.writer->close(error)) {
    if (error.empty()) error = "the image writer failed";
  }
  if (!error.empty()) {
    s.discard();
    s.finished = true;
    s.fail(error);
  }
}

void StripWriter::finish() {
  Impl& s = *impl_;
  close();
  std::error_code ec;
  fs::rename(s.temp, s.target, ec);
  if (ec) {
    s.discard();
    s.finished = true;
    s.fail(ec.message());
  }
  s.finished = true;
}

void write_channels(const fs::path& path, int width, int height, const WriteOptions& options, PixelType data_type,
                    const void* data) {
  StripWriter writer(path, width, height, options);
  writer.write_rows(0, height, data_type, data);
  writer.finish();
}

void write_animated_gif(const fs::path& path, const std::vector<std::vector<uint8_t>>& frames, int width,
                        int height, int fps) {
  if (frames.empty()) throw Error("no frames to write to " + quoted(path), "this is a bug in the caller");
  check_dimensions(width, height);
  for (const auto& f : frames) {
    if (f.size() != size_t(width) * height * 3) throw Error("GIF frames differ in size", "this is a bug in the caller");
  }
  detail::check_parent_directory(path);
  const fs::path temp = detail::create_temporary(path.parent_path() / (path.stem().string() + ".gif"));
  std::string error;
  bool ok = false;
  try {
    ok = backend::get("cannot write GIF " + quoted(path)).write_gif(temp.string(), frames, width, height, fps, error);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw;
  }
  std::error_code ec, ignored;
  if (ok) fs::rename(temp, path, ec);
  if (!ok || ec) {
    fs::remove(temp, ignored);
    throw Error("cannot write GIF " + quoted(path) + ": " + (ok ? ec.message() : error),
                "check that the folder is writable and the disk is not full");
  }
}

}  // namespace proctex
