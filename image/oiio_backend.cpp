// The OpenImageIO side of image/: built as a MODULE library (proctex_image_oiio.so) and loaded by
// image/backend_loader.cpp on first use, so that the proctex binary does not have OpenImageIO and
// its ~265 libraries in its DT_NEEDED list. Nothing here throws across the module boundary.
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <exception>

#include "image/backend.h"

namespace proctex::backend {
namespace {

// OIIO error strings can span several lines; our errors are one line.
std::string one_line(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text.empty() ? "unknown OpenImageIO error" : text;
}

// Collects (and thereby clears) every pending OIIO message, so OIIO never prints "pending error"
// warnings on stderr later and the user sees the cause in our message instead.
template <class Io>
std::string take_errors(const Io* io) {
  std::string text = io ? io->geterror() : std::string();
  std::string global = OIIO::geterror();
  if (!global.empty()) text += (text.empty() ? "" : "; ") + global;
  return one_line(text);
}

OIIO::TypeDesc oiio_type(PixelType t) {
  switch (t) {
    case PixelType::UInt8: return OIIO::TypeDesc::UINT8;
    case PixelType::UInt16: return OIIO::TypeDesc::UINT16;
    case PixelType::Half: return OIIO::TypeDesc::HALF;
    case PixelType::Float: return OIIO::TypeDesc::FLOAT;
  }
  return OIIO::TypeDesc::UINT8;
}

PixelType our_type(OIIO::TypeDesc t) {
  if (t.basetype == OIIO::TypeDesc::UINT8 || t.basetype == OIIO::TypeDesc::INT8) return PixelType::UInt8;
  if (t.basetype == OIIO::TypeDesc::HALF) return PixelType::Half;
  if (t.is_floating_point()) return PixelType::Float;
  return PixelType::UInt16;  // 16- and 32-bit integers: read as float, scaled to [0, 1]
}

class OiioReader final : public Reader {
 public:
  explicit OiioReader(std::unique_ptr<OIIO::ImageInput> in) : in_(std::move(in)) {
    const OIIO::ImageSpec& spec = in_->spec();
    header_.width = spec.width;
    header_.height = spec.height;
    header_.depth = spec.depth;
    header_.channels = spec.nchannels;
    header_.channel_names = spec.channelnames;
    header_.type = our_type(spec.format);
    header_.floating = spec.format.is_floating_point();
  }
  ~OiioReader() override {
    in_->close();
    take_errors(in_.get());  // drop warnings, so OIIO prints nothing later
  }
  const Header& header() const override { return header_; }
  bool read(int nchannels, float* data, std::ptrdiff_t pixel_stride, std::string& error) override {
    const bool ok = in_->read_image(0, 0, 0, nchannels, OIIO::TypeDesc::FLOAT, data, pixel_stride);
    // A truncated JPEG makes read_image return true (the rest is filled grey) and reports the
    // problem only through has_error(), so both are checked.
    if (!ok || in_->has_error()) {
      error = take_errors(in_.get());
      return false;
    }
    in_->close();
    if (in_->has_error()) {
      error = take_errors(in_.get());
      return false;
    }
    return true;
  }

 private:
  std::unique_ptr<OIIO::ImageInput> in_;
  Header header_;
};

class OiioWriter final : public Writer {
 public:
  explicit OiioWriter(std::unique_ptr<OIIO::ImageOutput> out) : out_(std::move(out)) {}
  ~OiioWriter() override {
    if (open_) out_->close();
    take_errors(out_.get());
  }
  bool write_rows(int y0, int y1, PixelType data_type, const void* data, std::string& error) override {
    // Return values decide: OpenImageIO's TIFF writer records "failed TIFFWriteCustomDirectory() of
    // the Exif data" for files without an sRGB colour space and still writes a good file.
    if (out_->write_scanlines(y0, y1, 0, oiio_type(data_type), data)) return true;
    error = take_errors(out_.get());
    return false;
  }
  bool close(std::string& error) override {
    open_ = false;
    if (out_->close()) {
      take_errors(out_.get());  // drop recorded warnings (see write_rows)
      return true;
    }
    error = take_errors(out_.get());
    return false;
  }

 private:
  std::unique_ptr<OIIO::ImageOutput> out_;
  bool open_ = true;
};


class OiioBackend final : public Backend {
 public:
  int interface_version() const override { return kInterfaceVersion; }

  std::unique_ptr<Reader> open_reader(const std::string& path, bool unassociated_alpha,
                                      std::string& error) override {
    try {
      OIIO::ImageSpec config;
      if (unassociated_alpha) config.attribute("oiio:UnassociatedAlpha", 1);
      auto in = OIIO::ImageInput::open(path, &config);
      if (!in) {
        error = take_errors<OIIO::ImageInput>(nullptr);
        return nullptr;
      }
      return std::make_unique<OiioReader>(std::move(in));
    } catch (const std::exception& e) {
      error = one_line(e.what());
      return nullptr;
    }
  }

  std::unique_ptr<Writer> open_writer(const std::string& path, int width, int height,
                                      const WriteOptions& o, std::string& error) override {
    try {
      auto out = OIIO::ImageOutput::create(path);
      if (!out) {
        error = take_errors<OIIO::ImageOutput>(nullptr);
        return nullptr;
      }
      OIIO::ImageSpec spec(width, height, o.channels, oiio_type(o.file_type));
      if (!o.channel_names.empty()) spec.channelnames = o.channel_names;
      if (!o.colour_space.empty()) spec.attribute("oiio:ColorSpace", o.colour_space);
      if (!o.compression.empty()) spec.attribute("compression", o.compression);
      if (o.png_compression_level >= 0) spec.attribute("png:compressionLevel", o.png_compression_level);
      for (const auto& [name, value] : o.attributes) spec.attribute(name, value);
      if (!out->open(path, spec)) {
        error = take_errors(out.get());
        return nullptr;
      }
      return std::make_unique<OiioWriter>(std::move(out));
    } catch (const std::exception& e) {
      error = one_line(e.what());
      return nullptr;
    }
  }

  bool write_gif(const std::string& path, const std::vector<std::vector<unsigned char>>& frames, int w, int h,
                 int fps, std::string& error) override {
    try {
      auto out = OIIO::ImageOutput::create(path);
      if (!out) {
        error = take_errors<OIIO::ImageOutput>(nullptr);
        return false;
      }
      if (!out->supports("multiimage") || !out->supports("appendsubimage")) {
        error = "this OpenImageIO cannot write animated GIFs";
        return false;
      }
      std::vector<OIIO::ImageSpec> specs;
      for (size_t i = 0; i < frames.size(); ++i) {
        OIIO::ImageSpec s(w, h, 3, OIIO::TypeDesc::UINT8);
        s.attribute("FramesPerSecond", OIIO::TypeRational, std::vector<int>{fps, 1}.data());
        s.attribute("gif:LoopCount", 0);  // loop forever
        specs.push_back(s);
      }
      bool ok = out->open(path, static_cast<int>(specs.size()), specs.data());
      for (size_t f = 0; ok && f < frames.size(); ++f) {
        if (f > 0) ok = out->open(path, specs[f], OIIO::ImageOutput::AppendSubimage);
        ok = ok && out->write_image(OIIO::TypeDesc::UINT8, frames[f].data());
      }
      ok = out->close() && ok;
      if (ok) {
        take_errors(out.get());
        return true;
      }
      error = take_errors(out.get());
      return false;
    } catch (const std::exception& e) {
      error = one_line(e.what());
      return false;
    }
  }

  int text_width(const std::string& text, int font_size, const std::string& font) override {
    OIIO::ROI roi = OIIO::ImageBufAlgo::text_size(text, font_size, font);
    OIIO::geterror();
    return roi.defined() ? roi.width() : -1;
  }

  bool render_text(float* rgb, int width, int height, int x, int y, const std::string& text, int font_size,
                   const std::string& font, const float colour[3]) override {
    // Wrap the caller's pixels so OIIO draws the text straight into them.
    OIIO::ImageBuf canvas(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT), rgb);
    const bool ok = OIIO::ImageBufAlgo::render_text(canvas, x, y, text, font_size, font, colour);
    take_errors(&canvas);
    return ok;
  }
};

}  // namespace
}  // namespace proctex::backend

extern "C" __attribute__((visibility("default"))) proctex::backend::Backend* proctex_image_backend_create() {
  static proctex::backend::OiioBackend backend;
  return &backend;
}
