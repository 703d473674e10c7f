#pragma once
// Sample thumbnails: small 8-bit sRGB PNGs stored as BLOBs in the catalogue.
#include <span>
#include <vector>

#include "image/image.h"

namespace proctex::catalog {

std::vector<unsigned char> encode_png(const Image& linear_rgb);
// Throws proctex::Error for bytes that are not a readable PNG.
Image decode_png(std::span<const unsigned char> png);

}  // namespace proctex::catalog
