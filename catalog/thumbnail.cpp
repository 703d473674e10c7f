#include "catalog/thumbnail.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "image/io.h"

namespace proctex::catalog {

std::vector<unsigned char> encode_png(const Image& img) {
  std::vector<unsigned char> bytes(img.pixels.size());
  for (size_t i = 0; i < bytes.size(); ++i) {
    const float v = std::clamp(linear_to_srgb(img.pixels[i]), 0.0f, 1.0f);
    bytes[i] = static_cast<unsigned char>(std::lround(v * 255.0f));
  }
  try {
    return proctex::encode_png(img.width, img.height, 3, bytes, 9);
  } catch (const Error& e) {
    throw Error("encoding a thumbnail failed: " + e.message(), e.hint());
  }
}

Image decode_png(std::span<const unsigned char> png) {
  ChannelImage decoded;
  try {
    decoded = proctex::decode_png(png);
  } catch (const Error& e) {
    throw Error("a catalogue thumbnail is not a readable PNG: " + e.message(),
                "the catalogue is damaged; rebuild the shader");
  }
  const int n = decoded.channels;
  Image img(decoded.width, decoded.height);
  for (size_t i = 0; i < size_t(decoded.width) * decoded.height; ++i)
    for (int c = 0; c < 3; ++c) {
      // Thumbnails are 8-bit: back to the code k, then k / 255 as before.
      img.pixels[3 * i + c] = srgb_to_linear(std::round(decoded.data[i * n + std::min(c, n - 1)] * 255.0f) / 255.0f);
    }
  return img;
}

}  // namespace proctex::catalog
