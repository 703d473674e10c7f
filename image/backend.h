#pragma once
// The interface between image/ and its OpenImageIO module (image/oiio_backend.cpp, built as the
// MODULE library proctex_image_oiio and loaded with dlopen by image/backend_loader.cpp). Internal
// to image/: other folders use image/image.h and image/io.h. Same compiler and standard library
// on both sides (built together); nothing throws across the boundary: failures return false and
// leave a one-line message in `error`.
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "image/io.h"

namespace proctex::backend {

// Bumped whenever this interface changes, so a stale module is refused instead of crashing.
inline constexpr int kInterfaceVersion = 1;

struct Header {
  int width = 0, height = 0, depth = 1, channels = 0;
  std::vector<std::string> channel_names;
  PixelType type = PixelType::UInt8;
  bool floating = false;  // the file stores float/half/double
};

class Reader {
 public:
  virtual ~Reader() = default;
  virtual const Header& header() const = 0;
  // Reads channels [0, nchannels) of the first subimage as float (integers scaled to [0, 1])
  // into `data`, `pixel_stride` bytes between pixels. Also reports problems a reader records
  // without failing (a truncated JPEG).
  virtual bool read(int nchannels, float* data, std::ptrdiff_t pixel_stride, std::string& error) = 0;
};

class Writer {
 public:
  virtual ~Writer() = default;  // closes an open file without reporting
  virtual bool write_rows(int y0, int y1, PixelType data_type, const void* data, std::string& error) = 0;
  virtual bool close(std::string& error) = 0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual int interface_version() const = 0;
  // `unassociated_alpha`: keep colour as stored (no premultiplication by alpha).
  virtual std::unique_ptr<Reader> open_reader(const std::string& path, bool unassociated_alpha,
                                              std::string& error) = 0;
  // The format comes from the extension of `path`.
  virtual std::unique_ptr<Writer> open_writer(const std::string& path, int width, int height,
                                              const WriteOptions& options, std::string& error) = 0;
  virtual bool write_gif(const std::string& path, const std::vector<std::vector<unsigned char>>& frames,
                         int width, int height, int fps, std::string& error) = 0;
  // Text for contact sheets: the width in pixels `text` takes (-1 if the font cannot be used),
  // and drawing into a float RGB canvas of width x height.
  virtual int text_width(const std::string& text, int font_size, const std::string& font) = 0;
  virtual bool render_text(float* rgb, int width, int height, int x, int y, const std::string& text,
                           int font_size, const std::string& font, const float colour[3]) = 0;
};

}  // namespace proctex::backend

// The module's one exported symbol.
extern "C" proctex::backend::Backend* proctex_image_backend_create();

namespace proctex::backend {
// The loaded backend (loads the module on first call; thread-safe). Throws proctex::Error naming
// what needed it (`purpose`, e.g. "cannot load image 'x.exr'") when the module cannot be loaded.
Backend& get(const std::string& purpose);
}  // namespace proctex::backend
