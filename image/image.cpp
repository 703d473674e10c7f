// Image I/O through OpenImageIO and the few pixel operations every folder needs.
#include "image/image.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>
#include <fcntl.h>
#include <unistd.h>

#include "core/error.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

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

const char* kLoadHint = "check that the file is a complete PNG, JPEG, TIFF or EXR image";

// --- PNG pre-check. libpng, called by OIIO 2.4, prints "libpng error: ..." on stderr before OIIO
// records the error, so a broken PNG would spam the terminal. Walking the chunk list first
// (lengths, CRCs, IEND) reports truncated and corrupted files quietly; only a crafted file with
// valid CRCs around a bad zlib stream still reaches libpng.
uint32_t crc32_update(uint32_t crc, const unsigned char* data, size_t n) {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  for (size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xff] ^ (crc >> 8);
  return crc;
}

uint32_t read_be32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

// Returns what is wrong with the PNG's chunk structure, "" if it looks whole (or is not a PNG).
std::string png_structure_problem(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char head[8];
  if (!in.read(reinterpret_cast<char*>(head), 8) ||
      std::memcmp(head, "\x89PNG\r\n\x1a\n", 8) != 0) {
    return {};
  }
  std::vector<unsigned char> buffer(1 << 16);
  while (true) {
    unsigned char header[8];
    if (!in.read(reinterpret_cast<char*>(header), 8)) return "truncated PNG (no IEND chunk)";
    const std::string type(reinterpret_cast<char*>(header) + 4, 4);
    uint32_t remaining = read_be32(header), crc = crc32_update(0xffffffffu, header + 4, 4);
    while (remaining > 0) {
      const size_t n = std::min<size_t>(remaining, buffer.size());
      if (!in.read(reinterpret_cast<char*>(buffer.data()), n)) {
        return "truncated PNG (chunk " + type + " is cut off)";
      }
      crc = crc32_update(crc, buffer.data(), n);
      remaining -= uint32_t(n);
    }
    unsigned char stored[4];
    if (!in.read(reinterpret_cast<char*>(stored), 4)) {
      return "truncated PNG (chunk " + type + " is cut off)";
    }
    if (read_be32(stored) != ~crc) return "corrupt PNG (checksum mismatch in chunk " + type + ")";
    if (type == "IEND") return {};
  }
}

// Lookup tables make linearising a 4096^2 photo cost no pow() calls.
std::vector<float> srgb_decode_table(int levels) {
  std::vector<float> table(levels);
  for (int i = 0; i < levels; ++i) table[i] = srgb_to_linear(float(i) / float(levels - 1));
  return table;
}

// OIIO delivers integer files as float k/(2^bits-1); undo that scale exactly and look up.
void linearise(std::vector<float>& values, OIIO::TypeDesc format) {
  if (!format.is_floating_point()) {
    const int levels = format.basetype == OIIO::TypeDesc::UINT8 ? 256 : 65536;
    const std::vector<float> table = srgb_decode_table(levels);
    const float scale = float(levels - 1);
    for (float& v : values) {
      v = table[std::clamp(static_cast<int>(std::lrint(v * scale)), 0, levels - 1)];
    }
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

// The file's pixel format and the buffer handed to OIIO, chosen by extension. Integer files get
// sRGB codes we round ourselves; EXR gets our linear floats, which OIIO converts to half.
struct Encoded {
  OIIO::ImageSpec spec;
  OIIO::TypeDesc data_format;
  std::vector<uint8_t> bytes;
  std::vector<uint16_t> words;
  const float* floats = nullptr;
  const void* data() const {
    return !bytes.empty() ? static_cast<const void*>(bytes.data())
           : !words.empty() ? static_cast<const void*>(words.data())
                            : static_cast<const void*>(floats);
  }
};

// data() is null for an extension we do not write.
Encoded encode_for_file(const Image& image, const std::string& ext) {
  Encoded e;
  e.spec = OIIO::ImageSpec(image.width, image.height, 3);
  if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") {
    e.bytes = encode_srgb<uint8_t>(image);
    e.data_format = OIIO::TypeDesc::UINT8;
    if (ext != ".png") e.spec.attribute("Compression", "jpeg:95");
    // Deflate level 1 instead of libpng's 6: faster to write (with the sRGB table, a 512^2 bricks
    // render 115 -> 25 ms, bench_image), the file 17 % larger; a morph writes hundreds of frames.
    else e.spec.attribute("png:compressionLevel", 1);
  } else if (ext == ".tif" || ext == ".tiff") {
    e.words = encode_srgb<uint16_t>(image);
    e.data_format = OIIO::TypeDesc::UINT16;
  } else if (ext == ".exr") {
    e.floats = image.pixels.data();
    e.data_format = OIIO::TypeDesc::FLOAT;
    e.spec.set_format(OIIO::TypeDesc::HALF);
    e.spec.attribute("oiio:ColorSpace", "Linear");
    return e;
  } else {
    return e;
  }
  e.spec.set_format(e.data_format);
  e.spec.attribute("oiio:ColorSpace", "sRGB");
  return e;
}

// Creates an empty, uniquely named file beside the target (same filesystem, so rename is atomic)
// that keeps the extension, because OIIO picks the format from it. Creating it ourselves gives
// the real reason (permission denied, read-only file system) when the directory is unwritable.
fs::path create_temporary(const fs::path& target) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  for (int attempt = 0;; ++attempt) {
    const fs::path temp = dir / ("." + target.stem().string() + ".tmp-" +
                                 std::to_string(getpid()) + "-" + std::to_string(counter++) +
                                 target.extension().string());
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      return temp;
    }
    if (errno != EEXIST || attempt > 100) {
      throw Error("cannot save image " + quoted(target) + ": cannot create a file in " +
                      quoted(dir) + ": " + std::strerror(errno),
                  "check that the directory is writable and the disk is not full");
    }
  }
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// Writes `data` (of type `data_format`; OIIO converts to spec.format) to `file`; returns an error
// text, empty on success.
std::string write_pixels(const fs::path& file, const OIIO::ImageSpec& spec,
                         OIIO::TypeDesc data_format, const void* data) {
  auto out = OIIO::ImageOutput::create(file.string());
  if (!out) return take_errors<OIIO::ImageOutput>(nullptr);
  bool ok = out->open(file.string(), spec) && out->write_image(data_format, data);
  ok = out->close() && ok;
  return ok && !out->has_error() ? std::string() : take_errors(out.get());
}

void check_parent_directory(const fs::path& path) {
  const fs::path dir = path.parent_path().empty() ? fs::path(".") : path.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw Error("cannot save image " + quoted(path) + ": directory " + quoted(dir) +
                    " does not exist",
                "create the directory first or choose another output path");
  }
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
    OIIO::ROI roi = OIIO::ImageBufAlgo::text_size(t, font_size, font);
    return roi.defined() && roi.width() <= width;
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
  if (const std::string problem = png_structure_problem(path); !problem.empty()) throw fail(problem);
  // Keep colour unassociated: OIIO would otherwise multiply it by the alpha we are about to drop.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path.string(), &config);
  if (!in) throw fail(take_errors<OIIO::ImageInput>(nullptr));
  auto close_and_fail = [&](const std::string& reason, const std::string& hint = kLoadHint) {
    in->close();
    const std::string oiio = take_errors(in.get());
    return fail(reason.empty() ? oiio : reason, hint);
  };

  // Only the header has been read so far: reject absurd sizes before allocating anything.
  const OIIO::ImageSpec spec = in->spec();
  try {
    check_dimensions(spec.width, spec.height, limits);
  } catch (const Error& e) {
    throw close_and_fail(e.message(), e.hint());
  }
  if (spec.depth > 1 || spec.nchannels < 1) {
    throw close_and_fail("unsupported layout (" + std::to_string(spec.nchannels) +
                         " channels, depth " + std::to_string(spec.depth) + ")");
  }

  Image image(spec.width, spec.height);
  // Grey and grey+alpha: read channel 0 only, straight into the red slot of each pixel.
  const int channels = spec.nchannels >= 3 ? 3 : 1;
  const bool ok = in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, image.pixels.data(),
                                 3 * sizeof(float));
  // A truncated JPEG makes read_image return true (the rest is filled grey) and reports the
  // problem only through has_error(), so both are checked.
  if (!ok || in->has_error()) throw close_and_fail("");
  in->close();
  if (in->has_error()) throw close_and_fail("");
  take_errors(in.get());  // drop warnings, so OIIO prints nothing later
  if (channels == 1) expand_grey(image);
  linearise(image.pixels, spec.format);
  return image;
}

void save_image(const Image& image, const fs::path& path) {
  if (image.empty() || image.pixels.size() != size_t(image.width) * image.height * 3) {
    throw Error("cannot save image " + quoted(path) + ": the image is empty or inconsistent (" +
                    std::to_string(image.width) + "x" + std::to_string(image.height) + ")",
                "this is a bug in the caller: produce an image before saving it");
  }
  const Encoded encoded = encode_for_file(image, lower_extension(path));
  if (!encoded.data()) {
    throw Error("cannot save image " + quoted(path) + ": unknown extension '" +
                    path.extension().string() + "'",
                "use .png, .jpg, .tif or .exr");
  }
  check_parent_directory(path);

  const fs::path temp = create_temporary(path);
  const std::string error = write_pixels(temp, encoded.spec, encoded.data_format, encoded.data());
  std::error_code rename_error, ignored;
  if (error.empty()) fs::rename(temp, path, rename_error);
  if (!error.empty() || rename_error) {
    fs::remove(temp, ignored);
    throw Error("cannot save image " + quoted(path) + ": " +
                    (error.empty() ? rename_error.message() : error),
                "check that the directory is writable and the disk is not full");
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

  // Wrap our pixels so OIIO draws the text straight into the sheet.
  OIIO::ImageBuf canvas(OIIO::ImageSpec(sheet.width, sheet.height, 3, OIIO::TypeDesc::FLOAT),
                        sheet.pixels.data());
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
    if (!text.empty() &&
        !OIIO::ImageBufAlgo::render_text(canvas, x0, y0 + tile_size + font_size, text, font_size,
                                         font, text_colour)) {
      take_errors(&canvas);
    }
  }
  take_errors(&canvas);
  return sheet;
}

}  // namespace proctex
