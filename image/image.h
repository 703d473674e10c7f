#pragma once
// Float linear-RGB images: the one pixel type every folder exchanges.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace proctex {

// Linear RGB, 3 floats per pixel, interleaved, row-major, top row first.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;

  Image() = default;
  Image(int w, int h, float fill = 0.0f);

  bool empty() const { return width <= 0 || height <= 0; }
  float* pixel(int x, int y) { return pixels.data() + 3 * (static_cast<size_t>(y) * width + x); }
  const float* pixel(int x, int y) const {
    return pixels.data() + 3 * (static_cast<size_t>(y) * width + x);
  }
};

// Limits that protect the process from absurd inputs (decompression bombs, typos in --size).
struct ImageLimits {
  int max_dimension = 65536;               // per side
  int64_t max_pixels = int64_t(1) << 28;   // 268 M pixels = 3.2 GB as float RGB
};

// Loads PNG, JPEG, TIFF, EXR (anything OpenImageIO reads; PNG and JPEG without loading it).
// 8/16-bit files are taken as sRGB and linearised; float files (EXR, float TIFF) as linear. Grey
// becomes RGB, alpha is dropped.
// Throws proctex::Error for a missing, truncated, corrupt, unsupported or oversized file.
Image load_image(const std::filesystem::path& path, const ImageLimits& limits = {});

// Saves by extension: .exr is linear half float; .png/.jpg/.tif are 8-bit sRGB (16-bit for .tif).
// Writes to a temporary file and renames, so a failed write never leaves a half file behind.
void save_image(const Image& image, const std::filesystem::path& path);

// Throws proctex::Error when w x h exceeds the limits (used before allocating renders too).
void check_dimensions(int w, int h, const ImageLimits& limits = {});

Image crop(const Image& image, int x, int y, int w, int h);
Image center_crop_square(const Image& image);
// Area-correct resize: every output pixel is the area-weighted mean of the input it covers.
Image resize(const Image& image, int w, int h);

float srgb_to_linear(float v);
float linear_to_srgb(float v);
// Rec. 709 luminance of one linear RGB pixel, and of every pixel of an image.
inline float luminance(const float* rgb) { return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2]; }
std::vector<float> luminance(const Image& image);

// Grid of images with a text label under each (used by the demo, galleries, catalogue sheets).
Image contact_sheet(const std::vector<Image>& tiles, const std::vector<std::string>& labels,
                    int columns, int tile_size);

}  // namespace proctex
