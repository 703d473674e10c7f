#pragma once
// Image files beyond load_image/save_image: any number of channels, files written strip by strip,
// PNG in memory, animated GIF. The only place in proctex that knows which library reads a format:
// PNG goes through libpng and JPEG reading through libjpeg (both linked into the binary); every
// other format through OpenImageIO in a plug-in module (proctex_image_oiio.so) that is loaded with
// dlopen on first use, so a command that only touches PNG (and reads JPEG) never maps
// OpenImageIO's ~265 libraries (docs/architecture.md, "Start-up").
// All writers are atomic: a temporary file beside the target, renamed into place when complete.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "image/image.h"

namespace proctex {

enum class PixelType { UInt8, UInt16, Half, Float };

// Every channel of a file as float. Integer files are scaled to [0, 1] (code / 255 or / 65535,
// no colour conversion); float files as stored.
struct ChannelImage {
  int width = 0, height = 0, channels = 0;
  std::vector<std::string> channel_names;  // "R", "G", "B", "A", "N.X", ...
  PixelType file_type = PixelType::UInt8;  // what the file stores
  std::vector<float> data;                 // interleaved, row-major, top row first
};

// Throws proctex::Error (one line naming the file) for a missing, corrupt or oversized file; the
// size is checked against `limits` before the pixels are allocated.
ChannelImage read_channels(const std::filesystem::path& path, const ImageLimits& limits = {});

// How a file is written. The format comes from the extension (.png, .tif/.tiff, .exr, .jpg/.jpeg).
struct WriteOptions {
  int channels = 3;
  PixelType file_type = PixelType::UInt8;  // PNG: UInt8/UInt16; EXR: Half/Float; TIFF: any
  std::vector<std::string> channel_names;  // empty: the format's defaults
  std::string colour_space;                // "sRGB", "Linear" or "" (recorded as metadata only)
  std::string compression;                 // e.g. "zip" (EXR), "jpeg:95" (JPEG); "" = default
  int png_compression_level = -1;          // zlib level 0-9 for PNG, -1 = libpng's default (6)
  int png_filter = -1;  // PNG row filters: a libpng PNG_FILTER_* mask, -1 = libpng's adaptive choice
  std::vector<std::pair<std::string, std::string>> attributes;  // extra string metadata (EXR)
};

// Writes a whole image: `data` holds width x height x options.channels values of `data_type`.
void write_channels(const std::filesystem::path& path, int width, int height, const WriteOptions& options,
                    PixelType data_type, const void* data);

// A file written in strips of rows, top to bottom, with bounded memory (PNG, TIFF, EXR and JPEG
// writers stream scanlines). finish() closes and renames into place; destroying an unfinished
// writer removes the temporary file. Errors throw proctex::Error naming the target.
class StripWriter {
 public:
  StripWriter(const std::filesystem::path& path, int width, int height, const WriteOptions& options);
  ~StripWriter();
  StripWriter(const StripWriter&) = delete;
  StripWriter& operator=(const StripWriter&) = delete;
  // Rows y0 .. y0 + rows - 1, in order; `data` holds width x rows x channels values of `data_type`.
  void write_rows(int y0, int rows, PixelType data_type, const void* data);
  // Closes the file after the last row (errors such as a full disk show here); optional: finish()
  // closes too. With several outputs, close all, then finish all: none is renamed unless all closed.
  void close();
  // Closes the file if needed and renames it into place.
  void finish();
  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// PNG in memory (catalogue thumbnails): width x height x channels (1-4) 8-bit codes in.
std::vector<unsigned char> encode_png(int width, int height, int channels, std::span<const uint8_t> codes,
                                      int compression_level = 9);
// Decodes an in-memory PNG (any bit depth, grey, alpha, palette) like read_channels does a file.
// Throws proctex::Error for bytes that are not a complete PNG.
ChannelImage decode_png(std::span<const unsigned char> png, const ImageLimits& limits = {});

// Animated GIF, looping: frames of width x height 8-bit RGB (sRGB codes), `fps` frames a second.
void write_animated_gif(const std::filesystem::path& path, const std::vector<std::vector<uint8_t>>& frames,
                        int width, int height, int fps);

// The image backend module (OpenImageIO), loaded on first use. Exposed for `--version`-style
// diagnostics and tests: true once loaded in this process; backend_module_path() is where it was
// (or would be) found, "" when it cannot be found.
bool image_backend_loaded();
std::filesystem::path image_backend_path();

}  // namespace proctex
