// libpng reading and writing. libpng reports errors by longjmp; every libpng call runs inside one
// of the small `guarded_*` functions below, which hold no C++ objects with destructors across the
// setjmp, and turn the jump into a false return. The message is kept in the Context.
#include "image/png_codec.h"

#include <png.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <csetjmp>
#include <cstring>

namespace proctex::png {
namespace {

struct Context {
  Source source;
  size_t position = 0;            // in memory
  std::vector<unsigned char>* sink = nullptr;
  std::FILE* out = nullptr;
  char message[256] = {0};        // libpng's error text, or ours from the I/O callbacks
  bool truncated = false;
};

void set_message(Context* c, const char* text) {
  std::strncpy(c->message, text, sizeof(c->message) - 1);
  c->message[sizeof(c->message) - 1] = 0;
}

void on_error(png_structp png, png_const_charp text) {
  auto* c = static_cast<Context*>(png_get_error_ptr(png));
  if (c->message[0] == 0) set_message(c, text ? text : "libpng error");
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}  // quiet: a warning never fails the image

void read_bytes(png_structp png, png_bytep data, size_t length) {
  auto* c = static_cast<Context*>(png_get_io_ptr(png));
  size_t got = 0;
  if (c->source.file) {
    got = std::fread(data, 1, length, c->source.file);
    if (got < length && std::ferror(c->source.file)) {
      set_message(c, std::strerror(errno));
      png_error(png, "read error");
    }
  } else {
    got = std::min(length, c->source.memory.size() - c->position);
    std::memcpy(data, c->source.memory.data() + c->position, got);
    c->position += got;
  }
  if (got < length) {
    c->truncated = true;
    png_error(png, "the file ends early");
  }
}

void write_bytes(png_structp png, png_bytep data, size_t length) {
  auto* c = static_cast<Context*>(png_get_io_ptr(png));
  if (c->out) {
    if (std::fwrite(data, 1, length, c->out) != length) {
      set_message(c, std::strerror(errno));
      png_error(png, "write error");
    }
  } else {
    c->sink->insert(c->sink->end(), data, data + length);
  }
}

void flush_bytes(png_structp) {}

// --- Guarded libpng calls (no destructors between setjmp and the libpng call).
bool guarded_read_info(png_structp png, png_infop info, int* passes) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  png_set_expand(png);  // palette -> RGB, grey < 8 bits -> 8, tRNS -> alpha
  // 16-bit samples in native order (PNG stores them big-endian).
  if (png_get_bit_depth(png, info) == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  *passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  return true;
}

bool guarded_read_rows(png_structp png, png_bytepp rows, png_uint_32 n) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_rows(png, rows, nullptr, n);
  return true;
}

bool guarded_read_end(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_end(png, info);
  return true;
}

bool guarded_write_info(png_structp png, png_infop info, const Header* h, int level, bool srgb, int filter) {
  if (setjmp(png_jmpbuf(png))) return false;
  static const int kColour[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                 PNG_COLOR_TYPE_RGB_ALPHA};
  png_set_IHDR(png, info, png_uint_32(h->width), png_uint_32(h->height), h->bit_depth, kColour[h->channels],
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (level >= 0) png_set_compression_level(png, std::clamp(level, 0, 9));
  if (filter >= 0) png_set_filter(png, PNG_FILTER_TYPE_BASE, filter);
  if (srgb) png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  if (h->bit_depth == 16 && std::endian::native == std::endian::little) png_set_swap(png);
  return true;
}

bool guarded_write_rows(png_structp png, png_bytepp rows, png_uint_32 n) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_write_rows(png, rows, n);
  return true;
}

bool guarded_write_end(png_structp png, png_infop info) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_write_end(png, info);
  return true;
}

struct ReadStructs {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~ReadStructs() { png_destroy_read_struct(&png, info ? &info : nullptr, nullptr); }
};

std::string read_problem(const Context& c) {
  if (c.truncated) return "truncated PNG (the file ends early)";
  return std::string("corrupt PNG (") + (c.message[0] ? c.message : "libpng error") + ")";
}

}  // namespace

bool has_signature(std::span<const unsigned char> head) {
  return head.size() >= 8 && png_sig_cmp(head.data(), 0, 8) == 0;
}

std::string decode(const Source& source, const std::function<void(const Header&)>& on_header,
                   const std::function<void(int, int, const unsigned char*)>& on_rows) {
  Context c;
  c.source = source;
  ReadStructs s;
  s.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &c, on_error, on_warning);
  if (!s.png) return "out of memory";
  s.info = png_create_info_struct(s.png);
  if (!s.info) return "out of memory";
  png_set_read_fn(s.png, &c, read_bytes);
  // Our ImageLimits decide (with a clear message) what is too large, not libpng's 1M default.
  png_set_user_limits(s.png, 0x7fffffff, 0x7fffffff);
  int passes = 1;
  if (!guarded_read_info(s.png, s.info, &passes)) return read_problem(c);

  Header h;
  h.width = int(png_get_image_width(s.png, s.info));
  h.height = int(png_get_image_height(s.png, s.info));
  h.channels = png_get_channels(s.png, s.info);
  h.bit_depth = png_get_bit_depth(s.png, s.info);
  on_header(h);  // may throw: nothing allocated yet but the libpng structs (freed by s)

  const size_t row_bytes = png_get_rowbytes(s.png, s.info);
  if (passes == 1) {
    // Non-interlaced: strips of rows, so memory stays a few rows beyond the caller's image.
    const int strip = int(std::clamp<size_t>((size_t(1) << 20) / std::max<size_t>(row_bytes, 1), 1, 256));
    std::vector<unsigned char> buffer(row_bytes * size_t(std::min(strip, h.height)));
    std::vector<png_bytep> rows(size_t(std::min(strip, h.height)));
    for (int y0 = 0; y0 < h.height; y0 += strip) {
      const int n = std::min(strip, h.height - y0);
      for (int r = 0; r < n; ++r) rows[size_t(r)] = buffer.data() + size_t(r) * row_bytes;
      if (!guarded_read_rows(s.png, rows.data(), png_uint_32(n))) return read_problem(c);
      on_rows(y0, n, buffer.data());
    }
  } else {
    // Interlaced: every pass touches every row, so the whole image is decoded first.
    std::vector<unsigned char> buffer(row_bytes * size_t(h.height));
    std::vector<png_bytep> rows(size_t(h.height));
    for (int r = 0; r < h.height; ++r) rows[size_t(r)] = buffer.data() + size_t(r) * row_bytes;
    for (int p = 0; p < passes; ++p) {
      if (!guarded_read_rows(s.png, rows.data(), png_uint_32(h.height))) return read_problem(c);
    }
    on_rows(0, h.height, buffer.data());
  }
  if (!guarded_read_end(s.png, s.info)) return read_problem(c);
  return {};
}

struct Encoder::State {
  Context context;
  Header header;
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::string error;  // the first failure; later calls repeat it
  std::vector<png_bytep> rows;
  ~State() { png_destroy_write_struct(&png, info ? &info : nullptr); }
  std::string fail() {
    if (error.empty()) error = context.message[0] ? context.message : "libpng error";
    return error;
  }
};

Encoder::Encoder(std::FILE* file, std::vector<unsigned char>* memory, const Header& header, int level, bool srgb,
                 int filter)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.header = header;
  s.context.out = file;
  s.context.sink = memory;
  s.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &s.context, on_error, on_warning);
  if (!s.png || !(s.info = png_create_info_struct(s.png))) {
    s.error = "out of memory";
    return;
  }
  png_set_write_fn(s.png, &s.context, write_bytes, flush_bytes);
  if (!guarded_write_info(s.png, s.info, &s.header, level, srgb, filter)) s.fail();
}

Encoder::~Encoder() = default;

std::string Encoder::write_rows(int n, const void* data) {
  State& s = *state_;
  if (!s.error.empty()) return s.error;
  const size_t row_bytes = size_t(s.header.width) * s.header.channels * (s.header.bit_depth / 8);
  s.rows.resize(size_t(n));
  auto* base = static_cast<png_bytep>(const_cast<void*>(data));
  for (int r = 0; r < n; ++r) s.rows[size_t(r)] = base + size_t(r) * row_bytes;
  if (!guarded_write_rows(s.png, s.rows.data(), png_uint_32(n))) return s.fail();
  return {};
}

std::string Encoder::finish() {
  State& s = *state_;
  if (!s.error.empty()) return s.error;
  if (!guarded_write_end(s.png, s.info)) return s.fail();
  return {};
}

}  // namespace proctex::png
