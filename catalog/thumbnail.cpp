#include "catalog/thumbnail.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace proctex::catalog {

std::vector<unsigned char> encode_png(const Image& img) {
  std::vector<unsigned char> bytes(img.pixels.size());
  for (size_t i = 0; i < bytes.size(); ++i) {
    const float v = std::clamp(linear_to_srgb(img.pixels[i]), 0.0f, 1.0f);
    bytes[i] = static_cast<unsigned char>(std::lround(v * 255.0f));
  }
  std::vector<unsigned char> out;
  OIIO::Filesystem::IOVecOutput proxy(out);
  auto writer = OIIO::ImageOutput::create("thumbnail.png");
  if (!writer) throw Error("cannot create a PNG writer: " + OIIO::geterror(), "OpenImageIO was built without PNG support");
  OIIO::ImageSpec spec(img.width, img.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("png:compressionLevel", 9);
  void* ptr = &proxy;
  spec.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &ptr);
  if (!writer->open("thumbnail.png", spec) || !writer->write_image(OIIO::TypeDesc::UINT8, bytes.data()) ||
      !writer->close())
    throw Error("encoding a thumbnail failed: " + writer->geterror());
  return out;
}

Image decode_png(std::span<const unsigned char> png) {
  OIIO::Filesystem::IOMemReader proxy(png.data(), png.size());
  OIIO::ImageSpec config;
  void* ptr = &proxy;
  config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &ptr);
  auto reader = OIIO::ImageInput::open("thumbnail.png", &config);
  if (!reader) throw Error("a catalogue thumbnail is not a readable PNG: " + OIIO::geterror(),
                           "the catalogue is damaged; rebuild the shader");
  const OIIO::ImageSpec& spec = reader->spec();
  std::vector<unsigned char> bytes(size_t(spec.width) * spec.height * spec.nchannels);
  if (!reader->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, bytes.data()))
    throw Error("a catalogue thumbnail could not be decoded: " + reader->geterror());
  Image img(spec.width, spec.height);
  for (int i = 0; i < spec.width * spec.height; ++i)
    for (int c = 0; c < 3; ++c)
      img.pixels[3 * size_t(i) + c] = srgb_to_linear(bytes[size_t(i) * spec.nchannels + std::min(c, spec.nchannels - 1)] / 255.0f);
  return img;
}

}  // namespace proctex::catalog
