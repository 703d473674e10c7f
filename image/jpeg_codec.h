#pragma once
// JPEG reading through libjpeg(-turbo), internal to image/: photos are often JPEG, and reading
// them here spares the OpenImageIO module's load (~0.1 s) for commands such as `proctex match`.
// Grey and YCbCr/RGB files only; CMYK/YCCK go to the module (decode returns kUnsupported).
#include <cstdio>
#include <functional>
#include <string>

namespace proctex::jpeg {

bool has_signature(const unsigned char* head, size_t n);

struct Header {
  int width = 0, height = 0;
  int channels = 0;  // 1 grey or 3 RGB
};

inline const char* kUnsupported = "unsupported";

// Decodes a whole JPEG from `file`. `on_header` runs before any pixel memory is allocated (it may
// throw); `on_rows(y0, rows, data)` receives consecutive 8-bit rows. Returns "" on success,
// kUnsupported for colour spaces we leave to OpenImageIO, else one line: "truncated JPEG (...)" or
// "corrupt JPEG (...)". Nothing is printed on stderr.
std::string decode(std::FILE* file, const std::function<void(const Header&)>& on_header,
                   const std::function<void(int y0, int rows, const unsigned char* data)>& on_rows);

}  // namespace proctex::jpeg
