// Image I/O (PNG through libpng, other formats through the OpenImageIO module, image/io.h) and
// the few pixel operations every folder needs.
#include "image/image.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>
#include <fcntl.h>
#include <unistd.h>

#include "core/error.h"
#include "image/backend.h"
#include "image/io.h"
#include "image/io_internal.h"
#include "image/jpeg_codec.h"
#include "image/png_codec.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;

using detail::quoted;

const char* kLoadHint = "check that the file is a complete PNG, JPEG, TIFF or EXR image";

// Lookup tables make linearising a 4096^2 photo cost no pow() calls.
std::vector<float> srgb_decode_table(int levels) {
  std::vector<float> table(levels);
  for (int i = 0; i < levels; ++i) table[i] = srgb_to_linear(float(i) / float(levels - 1));
  return table;
}

// The decoding table of 8- or 16-bit sRGB codes, built once.
const std::vector<float>& srgb_table(int bits) {
  static const std::vector<float> t8 = srgb_decode_table(256), t16 = srgb_decode_table(65536);
  return bits == 16 ? t16 : t8;
}

// The backend delivers integer files as float k/(2^bits-1); undo that scale exactly and look up.
void linearise(std::vector<float>& values, PixelType type) {
  if (type == PixelType::UInt8 || type == PixelType::UInt16) {
    const int levels = type == PixelType::UInt8 ? 256 : 65536;
    const std::vector<float>& table = srgb_table(type == PixelType::UInt8 ? 8 : 16);
    const float scale = float(levels - 1);
    for (float& v : values) {
      v = table[std::clamp(static_cast<int>(std::lrint(v * scale)), 0, levels - 1)];
    }
  }
}

// Rows of 8/16-bit codes, `channels` per pixel, into linear RGB. Grey and grey+alpha: channel 0
// to all three; alpha is dropped (never premultiplied).
template <class T>
void codes_to_linear(Image& image, int y0, int rows, const T* codes, int channels, const std::vector<float>& t) {
  const size_t n = size_t(rows) * image.width;
  float* dst = image.pixel(0, y0);
  if (channels >= 3) {
    for (size_t i = 0; i < n; ++i, codes += channels, dst += 3) {
      dst[0] = t[codes[0]], dst[1] = t[codes[1]], dst[2] = t[codes[2]];
    }
  } else {
    for (size_t i = 0; i < n; ++i, codes += channels, dst += 3) dst[0] = dst[1] = dst[2] = t[codes[0]];
  }
}

// Grey was read into channel 0 of each pixel; copy it to green and blue.
void expand_grey(Image& image) {
  for (size_t i = 0; i < image.pixels.size(); i += 3) {
    image.pixels[i + 1] = image.pixels[i + 2] = image.pixels[i];
  }
}

// Linear float -> integer code of `levels` sRGB steps, rounded to nearest. The table holds the
// linear value at each half step (code = how many of them v reaches); a second table gives that
// count at the start of 4 x `levels` equal buckets of [0, 1], so a code is a lookup plus a step
// or two instead of a binary search (which was a third of writing a PNG, measured with perf).
class SrgbEncoder {
 public:
  explicit SrgbEncoder(int levels) : thresholds_(levels - 1), buckets_(4 * levels), start_(buckets_ + 1) {
    for (int k = 0; k + 1 < levels; ++k) {
      thresholds_[k] = srgb_to_linear((k + 0.5f) / float(levels - 1));
    }
    for (int b = 0; b <= buckets_; ++b) {
      const float low = float(b) / float(buckets_);
      start_[b] = int(std::upper_bound(thresholds_.begin(), thresholds_.end(), low) - thresholds_.begin());
    }
  }
  int operator()(float v) const {
    if (!(v > 0.0f)) return 0;  // also maps NaN to black
    const int last = int(thresholds_.size());
    if (v >= 1.0f) return last;
    int k = start_[std::min(int(v * float(buckets_)), buckets_)];
    while (k < last && thresholds_[k] <= v) ++k;   // exact whatever the bucket's rounding
    while (k > 0 && thresholds_[k - 1] > v) --k;
    return k;
  }

 private:
  std::vector<float> thresholds_;
  int buckets_;
  std::vector<int> start_;
};

template <class T>
std::vector<T> encode_srgb(const Image& image) {
  static const SrgbEncoder encode(int(std::numeric_limits<T>::max()) + 1);  // built once, read-only
  std::vector<T> out(image.pixels.size());
  std::transform(image.pixels.begin(), image.pixels.end(), out.begin(),
                 [&](float v) { return static_cast<T>(encode(v)); });
  return out;
}

float area_overlap(double a0, double a1, double b0, double b1) {
  return float(std::max(0.0, std::min(a1, b1) - std::max(a0, b0)));
}

// For one axis: which input pixels each output pixel covers, with weights = covered length /
// output footprint, so the weights of one output sum to 1 and the mean is preserved exactly.
struct Contribution {
  int first = 0;
  std::vector<float> weights;
};

std::vector<Contribution> box_weights(int in_size, int out_size) {
  const double scale = double(in_size) / double(out_size);
  std::vector<Contribution> result(out_size);
  for (int o = 0; o < out_size; ++o) {
    const double a = o * scale, b = (o + 1) * scale;
    const int first = int(std::floor(a));
    const int last = std::min(in_size - 1, int(std::ceil(b)) - 1);
    result[o].first = first;
    for (int i = first; i <= last; ++i) {
      result[o].weights.push_back(area_overlap(a, b, i, i + 1) / float(scale));
    }
  }
  return result;
}

// Font for contact-sheet labels: DejaVu (Debian fonts-dejavu-core), else OIIO's default search.
std::string label_font() {
  const char* dejavu = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
  std::error_code ec;
  return fs::exists(dejavu, ec) ? dejavu : "";
}

// Shortens a label with "..." until it fits `width` pixels; empty if even that does not fit or the
// font is unavailable (text_size fails), which the caller treats as "no text".
std::string fit_label(std::string text, int width, int font_size, const std::string& font) {
  auto fits = [&](const std::string& t) {
    const int w = backend::get("cannot draw contact-sheet labels").text_width(t, font_size, font);
    return w >= 0 && w <= width;
  };
  if (text.empty() || fits(text)) return text;
  while (!text.empty()) {
    text.pop_back();
    if (fits(text + "...")) return text + "...";
  }
  return {};
}

void paste(Image& dst, const Image& tile, int x0, int y0) {
  for (int y = 0; y < tile.height; ++y) {
    std::copy(tile.pixel(0, y), tile.pixel(0, y) + 3 * tile.width, dst.pixel(x0, y0 + y));
  }
}

}  // namespace

Image::Image(int w, int h, float fill)
    : width(w), height(h), pixels(size_t(std::max(w, 0)) * size_t(std::max(h, 0)) * 3, fill) {}

void check_dimensions(int w, int h, const ImageLimits& limits) {
  const std::string size = std::to_string(w) + "x" + std::to_string(h);
  if (w <= 0 || h <= 0) {
    throw Error("invalid image size " + size + ": width and height must be positive",
                "use a size of at least 1x1");
  }
  if (w > limits.max_dimension || h > limits.max_dimension ||
      int64_t(w) * int64_t(h) > limits.max_pixels) {
    throw Error("image size " + size + " exceeds the limit of " +
                    std::to_string(limits.max_dimension) + " pixels per side and " +
                    std::to_string(limits.max_pixels) + " pixels in total",
                "use a smaller image or size");
  }
}

Image load_image(const fs::path& path, const ImageLimits& limits) {
  auto fail = [&](const std::string& reason, const std::string& hint = kLoadHint) {
    return Error("cannot load image " + quoted(path) + ": " + reason, hint);
  };
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) {
    throw fail(fs::exists(path, ec) ? "not a regular file" : "file not found", "check the path");
  }
  if (fs::file_size(path, ec) == 0 && !ec) throw fail("the file is empty");

  Image image;
  const detail::Format format = detail::sniff(path);
  if (format == detail::Format::Png || format == detail::Format::Jpeg) {
    // PNG (libpng) and JPEG (libjpeg): codes straight through the sRGB table, no float round trip.
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) throw fail(std::strerror(errno), "check the file's permissions");
    int channels = 0, bits = 8;
    auto on_header = [&](int w, int h, int c, int depth) {
      // Only the header has been read so far: reject absurd sizes before allocating anything.
      try {
        check_dimensions(w, h, limits);
      } catch (const Error& e) {
        throw fail(e.message(), e.hint());
      }
      channels = c, bits = depth;
      image = Image(w, h);
    };
    auto on_rows = [&](int y0, int rows, const unsigned char* data) {
      if (bits == 16) {
        codes_to_linear(image, y0, rows, reinterpret_cast<const uint16_t*>(data), channels, srgb_table(16));
      } else {
        codes_to_linear(image, y0, rows, data, channels, srgb_table(8));
      }
    };
    std::string problem;
    try {
      if (format == detail::Format::Png) {
        png::Source source;
        source.file = file;
        problem = png::decode(
            source, [&](const png::Header& h) { on_header(h.width, h.height, h.channels, h.bit_depth); }, on_rows);
      } else {
        problem = jpeg::decode(
            file, [&](const jpeg::Header& h) { on_header(h.width, h.height, h.channels, 8); }, on_rows);
      }
    } catch (...) {
      std::fclose(file);
      throw;
    }
    std::fclose(file);
    if (problem.empty()) return image;
    if (problem != jpeg::kUnsupported) throw fail(problem);
    image = Image();  // a CMYK JPEG: OpenImageIO converts it
  }

  // Every other format: the OpenImageIO module. Colour is kept unassociated: OIIO would otherwise
  // multiply it by the alpha we are about to drop.
  std::string error;
  auto in = backend::get("cannot load image " + quoted(path)).open_reader(path.string(), true, error);
  if (!in) throw fail(error);
  const backend::Header& spec = in->header();
  try {
    check_dimensions(spec.width, spec.height, limits);
  } catch (const Error& e) {
    throw fail(e.message(), e.hint());
  }
  if (spec.depth > 1 || spec.channels < 1) {
    throw fail("unsupported layout (" + std::to_string(spec.channels) + " channels, depth " +
               std::to_string(spec.depth) + ")");
  }
  image = Image(spec.width, spec.height);
  // Grey and grey+alpha: read channel 0 only, straight into the red slot of each pixel.
  const int channels = spec.channels >= 3 ? 3 : 1;
  if (!in->read(channels, image.pixels.data(), 3 * sizeof(float), error)) throw fail(error);
  if (channels == 1) expand_grey(image);
  if (!spec.floating) linearise(image.pixels, spec.type);
  return image;
}

void save_image(const Image& image, const fs::path& path) {
  if (image.empty() || image.pixels.size() != size_t(image.width) * image.height * 3) {
    throw Error("cannot save image " + quoted(path) + ": the image is empty or inconsistent (" +
                    std::to_string(image.width) + "x" + std::to_string(image.height) + ")",
                "this is a bug in the caller: produce an image before saving it");
  }
  // The file's pixel type chosen by extension. Integer files get sRGB codes we round ourselves;
  // EXR gets our linear floats, which OpenImageIO converts to half.
  const std::string ext = detail::lower_extension(path);
  WriteOptions options;
  options.colour_space = "sRGB";
  if (ext == ".png") {
    // Deflate level 1 instead of libpng's 6: faster to write (with the sRGB table, a 512^2 bricks
    // render 115 -> 25 ms, bench_image), the file 17 % larger; a morph writes hundreds of frames.
    options.png_compression_level = 1;
    write_channels(path, image.width, image.height, options, PixelType::UInt8, encode_srgb<uint8_t>(image).data());
  } else if (ext == ".jpg" || ext == ".jpeg") {
    options.compression = "jpeg:95";
    write_channels(path, image.width, image.height, options, PixelType::UInt8, encode_srgb<uint8_t>(image).data());
  } else if (ext == ".tif" || ext == ".tiff") {
    options.file_type = PixelType::UInt16;
    write_channels(path, image.width, image.height, options, PixelType::UInt16,
                   encode_srgb<uint16_t>(image).data());
  } else if (ext == ".exr") {
    options.file_type = PixelType::Half;
    options.colour_space = "Linear";
    write_channels(path, image.width, image.height, options, PixelType::Float, image.pixels.data());
  } else {
    throw Error("cannot save image " + quoted(path) + ": unknown extension '" + path.extension().string() + "'",
                "use .png, .jpg, .tif or .exr");
  }
}

Image crop(const Image& image, int x, int y, int w, int h) {
  if (w <= 0 || h <= 0 || x < 0 || y < 0 || int64_t(x) + w > image.width ||
      int64_t(y) + h > image.height) {
    throw Error("crop " + std::to_string(w) + "x" + std::to_string(h) + " at (" +
                    std::to_string(x) + ", " + std::to_string(y) + ") lies outside the " +
                    std::to_string(image.width) + "x" + std::to_string(image.height) + " image",
                "choose a crop rectangle inside the image");
  }
  Image out(w, h);
  for (int row = 0; row < h; ++row) {
    std::copy(image.pixel(x, y + row), image.pixel(x, y + row) + 3 * w, out.pixel(0, row));
  }
  return out;
}

Image center_crop_square(const Image& image) {
  const int side = std::min(image.width, image.height);
  return crop(image, (image.width - side) / 2, (image.height - side) / 2, side, side);
}

Image resize(const Image& image, int w, int h) {
  if (image.empty()) throw Error("cannot resize an empty image", "load or render an image first");
  check_dimensions(w, h);
  if (w == image.width && h == image.height) return image;
  // Separable: rows first (cheap, contiguous), then columns of the already-narrowed image.
  const std::vector<Contribution> cols = box_weights(image.width, w);
  const std::vector<Contribution> rows = box_weights(image.height, h);
  Image narrow(w, image.height);
  for (int y = 0; y < image.height; ++y) {
    const float* src = image.pixel(0, y);
    float* dst = narrow.pixel(0, y);
    for (int x = 0; x < w; ++x) {
      float r = 0, g = 0, b = 0;
      const float* p = src + 3 * cols[x].first;
      for (float weight : cols[x].weights) {
        r += weight * p[0], g += weight * p[1], b += weight * p[2];
        p += 3;
      }
      dst[3 * x] = r, dst[3 * x + 1] = g, dst[3 * x + 2] = b;
    }
  }
  // Columns: accumulate whole weighted rows so the inner loop runs over contiguous memory.
  Image out(w, h);
  const size_t row_length = size_t(3) * w;
  for (int y = 0; y < h; ++y) {
    float* dst = out.pixel(0, y);
    const Contribution& c = rows[y];
    for (size_t k = 0; k < c.weights.size(); ++k) {
      const float* src = narrow.pixel(0, c.first + int(k));
      const float weight = c.weights[k];
      for (size_t i = 0; i < row_length; ++i) dst[i] += weight * src[i];
    }
  }
  return out;
}

// The exact piecewise IEC 61966-2-1 curves (not the 2.2 gamma approximation).
float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

float linear_to_srgb(float v) {
  return v <= 0.0031308f ? v * 12.92f : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

std::vector<float> luminance(const Image& image) {
  std::vector<float> out(size_t(std::max(image.width, 0)) * std::max(image.height, 0));
  for (size_t i = 0; i < out.size(); ++i) out[i] = luminance(image.pixels.data() + 3 * i);
  return out;
}

Image contact_sheet(const std::vector<Image>& tiles, const std::vector<std::string>& labels,
                    int columns, int tile_size) {
  if (tiles.empty() || columns <= 0 || tile_size <= 0) {
    throw Error("contact sheet needs at least one tile, columns > 0 and tile size > 0",
                "pass tiles and a positive layout");
  }
  const int cols = std::min<int>(columns, int(tiles.size()));
  const int rows = int((tiles.size() + cols - 1) / cols);
  const int margin = std::max(4, tile_size / 16);
  const int font_size = std::clamp(tile_size / 10, 10, 24);
  const int label_height = font_size + font_size / 2;
  const int cell_w = tile_size + margin, cell_h = tile_size + label_height + margin;
  check_dimensions(cols * cell_w + margin, rows * cell_h + margin);
  Image sheet(cols * cell_w + margin, rows * cell_h + margin, 0.02f);  // dark grey (sRGB ~0.15)

  const std::string font = label_font();
  const float text_colour[3] = {0.8f, 0.8f, 0.8f};
  for (size_t i = 0; i < tiles.size(); ++i) {
    const int x0 = margin + int(i % cols) * cell_w, y0 = margin + int(i / cols) * cell_h;
    if (!tiles[i].empty()) {
      const bool fits = tiles[i].width == tile_size && tiles[i].height == tile_size;
      // Crop to a square first so non-square tiles are not stretched.
      paste(sheet, fits ? tiles[i] : resize(center_crop_square(tiles[i]), tile_size, tile_size),
            x0, y0);
    }
    const std::string text =
        i < labels.size() ? fit_label(labels[i], tile_size, font_size, font) : "";
    // A missing font is not worth failing a gallery for: the tiles alone are still useful.
    if (!text.empty()) {
      backend::get("cannot draw contact-sheet labels")
          .render_text(sheet.pixels.data(), sheet.width, sheet.height, x0, y0 + tile_size + font_size, text,
                       font_size, font, text_colour);
    }
  }
  return sheet;
}

}  // namespace proctex
