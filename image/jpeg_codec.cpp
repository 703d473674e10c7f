// libjpeg reading. As with libpng (png_codec.cpp), libjpeg's error_exit longjmps: every libjpeg
// call runs in a small `guarded_*` function without C++ objects across the setjmp.
#include "image/jpeg_codec.h"

#include <jpeglib.h>
#include <jerror.h>

#include <algorithm>
#include <csetjmp>
#include <cstring>
#include <vector>

namespace proctex::jpeg {
namespace {

struct ErrorManager {
  jpeg_error_mgr pub;  // first: libjpeg sees an ErrorManager* as a jpeg_error_mgr*
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX] = {0};
  bool truncated = false;
};

void on_error_exit(j_common_ptr cinfo) {
  auto* e = reinterpret_cast<ErrorManager*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, e->message);
  std::longjmp(e->jump, 1);
}

// Warnings are not printed. A premature end of the data (libjpeg pads it with grey and warns) is
// an error for us: the image would be silently incomplete.
void on_emit_message(j_common_ptr cinfo, int level) {
  auto* e = reinterpret_cast<ErrorManager*>(cinfo->err);
  if (level < 0 && cinfo->err->msg_code == JWRN_JPEG_EOF) e->truncated = true;
}

bool guarded_start(jpeg_decompress_struct* c, ErrorManager* e, std::FILE* f, bool* supported) {
  if (setjmp(e->jump)) return false;
  jpeg_create_decompress(c);
  jpeg_stdio_src(c, f);
  jpeg_read_header(c, TRUE);
  *supported = c->jpeg_color_space == JCS_GRAYSCALE || c->jpeg_color_space == JCS_YCbCr ||
               c->jpeg_color_space == JCS_RGB;
  if (!*supported) return true;
  c->out_color_space = c->jpeg_color_space == JCS_GRAYSCALE ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(c);
  return true;
}

bool guarded_read(jpeg_decompress_struct* c, ErrorManager* e, JSAMPARRAY rows, JDIMENSION n, JDIMENSION* got) {
  if (setjmp(e->jump)) return false;
  *got = jpeg_read_scanlines(c, rows, n);
  return true;
}

bool guarded_finish(jpeg_decompress_struct* c, ErrorManager* e) {
  if (setjmp(e->jump)) return false;
  jpeg_finish_decompress(c);
  return true;
}

struct Decompressor {
  jpeg_decompress_struct info{};
  ErrorManager error;
  Decompressor() {
    info.err = jpeg_std_error(&error.pub);
    error.pub.error_exit = on_error_exit;
    error.pub.emit_message = on_emit_message;
  }
  ~Decompressor() { jpeg_destroy_decompress(&info); }
  std::string problem() const {
    if (error.truncated) return "truncated JPEG (the file ends early)";
    return std::string("corrupt JPEG (") + (error.message[0] ? error.message : "libjpeg error") + ")";
  }
};

}  // namespace

bool has_signature(const unsigned char* head, size_t n) {
  return n >= 3 && head[0] == 0xff && head[1] == 0xd8 && head[2] == 0xff;
}

std::string decode(std::FILE* file, const std::function<void(const Header&)>& on_header,
                   const std::function<void(int, int, const unsigned char*)>& on_rows) {
  Decompressor d;
  bool supported = true;
  if (!guarded_start(&d.info, &d.error, file, &supported)) return d.problem();
  if (!supported) return kUnsupported;
  Header h;
  h.width = int(d.info.output_width);
  h.height = int(d.info.output_height);
  h.channels = d.info.output_components;
  on_header(h);  // may throw: ~Decompressor releases libjpeg's memory
  const size_t row_bytes = size_t(h.width) * h.channels;
  const int strip = int(std::clamp<size_t>((size_t(1) << 20) / std::max<size_t>(row_bytes, 1), 1, 64));
  std::vector<unsigned char> buffer(row_bytes * size_t(strip));
  std::vector<JSAMPROW> rows(static_cast<size_t>(strip));
  for (int r = 0; r < strip; ++r) rows[size_t(r)] = buffer.data() + size_t(r) * row_bytes;
  int y = 0;
  while (y < h.height) {
    JDIMENSION got = 0;
    const int want = std::min(strip, h.height - y);
    // jpeg_read_scanlines may return fewer rows than asked: loop until the strip is full.
    int filled = 0;
    while (filled < want) {
      if (!guarded_read(&d.info, &d.error, rows.data() + filled, JDIMENSION(want - filled), &got)) return d.problem();
      if (got == 0) return d.problem();
      filled += int(got);
    }
    if (d.error.truncated) return d.problem();
    on_rows(y, want, buffer.data());
    y += want;
  }
  if (!guarded_finish(&d.info, &d.error) || d.error.truncated) return d.problem();
  return {};
}

}  // namespace proctex::jpeg
