#pragma once
// PNG through libpng, internal to image/ (image/io.h and image/image.h are the API). Reads any
// PNG (1-16 bit, grey, grey+alpha, palette, RGB, RGBA, interlaced) as 8- or 16-bit codes with the
// stored channels (palette expanded to RGB, transparency to alpha); writes 8/16-bit grey to RGBA
// row by row. libpng's messages never reach stderr: they become one-line errors.
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace proctex::png {

bool has_signature(std::span<const unsigned char> head);

struct Header {
  int width = 0, height = 0;
  int channels = 0;   // 1 grey, 2 grey+alpha, 3 RGB, 4 RGBA (after expansion)
  int bit_depth = 8;  // 8 or 16 (16-bit codes in native byte order)
};

// Where the bytes come from: a file or memory.
struct Source {
  std::FILE* file = nullptr;
  std::span<const unsigned char> memory;
};

// Decodes a whole PNG. `on_header` runs after the header is read and before any pixel memory is
// allocated (it may throw to refuse the image); `on_rows(y0, rows, data)` receives consecutive
// rows (width x channels codes of bit_depth each) top to bottom. Returns an error text ("" on
// success): "truncated PNG (...)" or "corrupt PNG (...)". Exceptions from the callbacks pass.
std::string decode(const Source& source, const std::function<void(const Header&)>& on_header,
                   const std::function<void(int y0, int rows, const unsigned char* data)>& on_rows);

// Streams a PNG out row by row: to a FILE (not closed) or, if `file` is null, to `memory`.
class Encoder {
 public:
  // `filter`: a PNG_FILTER_* mask of the row filters libpng may choose from, -1 = its default.
  Encoder(std::FILE* file, std::vector<unsigned char>* memory, const Header& header, int compression_level,
          bool srgb, int filter = -1);
  ~Encoder();
  Encoder(const Encoder&) = delete;
  Encoder& operator=(const Encoder&) = delete;
  // `rows` rows of width x channels codes (uint8 or native uint16). "" on success, else why not.
  std::string write_rows(int rows, const void* data);
  std::string finish();  // after the last row
  struct State;

 private:
  std::unique_ptr<State> state_;
};

}  // namespace proctex::png
