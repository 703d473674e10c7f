// image/io.h: the libpng path (8/16-bit, grey, alpha, palette, strips, memory, bad files) and the
// OpenImageIO module loaded on first use (EXR round trips, the binary starts without OpenImageIO,
// a missing module is one clear error).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <algorithm>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.h"
#include "image/image.h"
#include "image/io.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace fs = std::filesystem;
using proctex::ChannelImage;
using proctex::Error;
using proctex::Image;
using proctex::PixelType;
using proctex::WriteOptions;
using proctex::testing::TempDir;

namespace {

const fs::path kTextures = fs::path(PROCTEX_SHARED_DIR) / "textures";

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const fs::path& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// --- A minimal PNG writer (stored deflate blocks), independent of libpng, for crafted files.
uint32_t crc32(const std::string& data) {
  uint32_t crc = 0xffffffffu;
  for (unsigned char c : data) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}
std::string be32(uint32_t v) { return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)}; }
std::string chunk(const std::string& type, const std::string& data) {
  return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}
std::string zlib_stored(const std::string& raw) {
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  std::string out = "\x78\x01";
  for (size_t pos = 0; pos == 0 || pos < raw.size(); pos += 65535) {
    const size_t n = std::min<size_t>(65535, raw.size() - pos);
    out += char(pos + n >= raw.size() ? 1 : 0);
    out += {char(n & 0xff), char(n >> 8), char(~n & 0xff), char((~n >> 8) & 0xff)};
    out += raw.substr(pos, n);
  }
  return out + be32((b << 16) | a);
}
// `extra` chunks (PLTE, tRNS) go between IHDR and IDAT.
std::string make_png(uint32_t w, uint32_t h, int depth, int colour, const std::vector<std::string>& rows,
                     const std::string& extra = "") {
  const std::string ihdr = be32(w) + be32(h) + char(depth) + char(colour) + '\0' + '\0' + '\0';
  std::string raw;
  for (const auto& row : rows) raw += '\0' + row;
  return std::string("\x89PNG\r\n\x1a\n") + chunk("IHDR", ihdr) + extra + chunk("IDAT", zlib_stored(raw)) +
         chunk("IEND", "");
}

std::string error_of(const std::function<void()>& f) {
  ::testing::internal::CaptureStderr();
  std::string message = "(no error)";
  try {
    f();
  } catch (const Error& e) {
    message = e.message();
    EXPECT_FALSE(e.hint().empty());
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "") << "a library printed on stderr";
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  return message;
}

bool mapped(const std::string& library) {
  return read_bytes("/proc/self/maps").find(library) != std::string::npos;
}

}  // namespace

// ctest runs each test in its own process: nothing has needed the module yet, so PNG work must
// not load OpenImageIO. The test binary links only proctex_image (not OpenImageIO).
TEST(ImageBackend, PngWorkDoesNotLoadOpenImageIo) {
  if (proctex::image_backend_loaded()) GTEST_SKIP() << "an earlier test in this process loaded the module";
  TempDir dir;
  const Image brick = proctex::load_image(kTextures / "brick.png");
  proctex::save_image(brick, dir / "b.png");
  proctex::read_channels(dir / "b.png");
  const Image hubble = proctex::load_image(kTextures / "hubble_deep_field.jpg");  // libjpeg
  EXPECT_GT(hubble.width, 0);
  EXPECT_FALSE(proctex::image_backend_loaded());
  EXPECT_FALSE(mapped("libOpenImageIO"));
}

TEST(PngCodec, SixteenBitRoundTripIsExactForEveryChannelCount) {
  TempDir dir;
  for (int channels = 1; channels <= 4; ++channels) {
    const int w = 37, h = 23;
    std::vector<uint16_t> codes(size_t(w) * h * channels);
    for (size_t i = 0; i < codes.size(); ++i) codes[i] = uint16_t((i * 2654435761u) >> 7);  // all bits vary
    WriteOptions o;
    o.channels = channels;
    o.file_type = PixelType::UInt16;
    const fs::path path = dir / ("c" + std::to_string(channels) + ".png");
    proctex::write_channels(path, w, h, o, PixelType::UInt16, codes.data());
    const ChannelImage back = proctex::read_channels(path);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    ASSERT_EQ(back.channels, channels);
    EXPECT_EQ(back.file_type, PixelType::UInt16);
    for (size_t i = 0; i < codes.size(); ++i) ASSERT_EQ(std::lround(back.data[i] * 65535.0f), codes[i]) << i;
  }
}

TEST(PngCodec, SixteenBitSaveImageKeepsSixteenBitPrecision) {
  TempDir dir;
  // A ramp finer than 8 bits: a 16-bit file tells neighbours apart that an 8-bit one merges.
  std::vector<uint16_t> codes(256 * 3);
  for (size_t i = 0; i < codes.size(); ++i) codes[i] = uint16_t(30000 + i / 3);
  WriteOptions o;
  o.file_type = PixelType::UInt16;
  proctex::write_channels(dir / "ramp.png", 256, 1, o, PixelType::UInt16, codes.data());
  const Image img = proctex::load_image(dir / "ramp.png");
  for (int x = 0; x < 256; ++x) {
    EXPECT_FLOAT_EQ(img.pixel(x, 0)[0], proctex::srgb_to_linear((30000 + x) / 65535.0f));
    if (x) {
      EXPECT_GT(img.pixel(x, 0)[0], img.pixel(x - 1, 0)[0]);
    }
  }
}

TEST(PngCodec, StripsWrittenInPiecesEqualTheWholeImage) {
  TempDir dir;
  const int w = 50, h = 41;
  std::vector<uint8_t> codes(size_t(w) * h * 3);
  for (size_t i = 0; i < codes.size(); ++i) codes[i] = uint8_t(i * 7 + i / 151);
  WriteOptions o;
  {
    proctex::StripWriter writer(dir / "s.png", w, h, o);
    for (int y0 = 0; y0 < h; y0 += 8) {
      const int rows = std::min(8, h - y0);
      writer.write_rows(y0, rows, PixelType::UInt8, codes.data() + size_t(y0) * w * 3);
    }
    EXPECT_FALSE(fs::exists(dir / "s.png")) << "visible before finish()";
    writer.finish();
  }
  const ChannelImage back = proctex::read_channels(dir / "s.png");
  for (size_t i = 0; i < codes.size(); ++i) ASSERT_EQ(std::lround(back.data[i] * 255.0f), codes[i]);
  // An unfinished writer leaves nothing behind.
  { proctex::StripWriter abandoned(dir / "t.png", w, h, o); }
  size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1u);
}

TEST(PngCodec, RgbaKeepsColourUnpremultipliedAndLoadDropsAlpha) {
  TempDir dir;
  // 2x1 RGBA: (200, 100, 50, alpha 0) and (10, 20, 30, alpha 128).
  write_bytes(dir / "rgba.png", make_png(2, 1, 8, 6, {std::string("\xc8\x64\x32\x00\x0a\x14\x1e\x80", 8)}));
  const ChannelImage raw = proctex::read_channels(dir / "rgba.png");
  ASSERT_EQ(raw.channels, 4);
  EXPECT_EQ(std::lround(raw.data[0] * 255), 200);
  EXPECT_EQ(std::lround(raw.data[3] * 255), 0);
  EXPECT_EQ(std::lround(raw.data[7] * 255), 128);
  const Image img = proctex::load_image(dir / "rgba.png");
  EXPECT_FLOAT_EQ(img.pixel(0, 0)[0], proctex::srgb_to_linear(200 / 255.0f));
  EXPECT_FLOAT_EQ(img.pixel(1, 0)[2], proctex::srgb_to_linear(30 / 255.0f));
}

TEST(PngCodec, PaletteAndLowBitGreyAreExpanded) {
  TempDir dir;
  // 2-bit palette image, 3 pixels: indices 0, 1, 2 -> red, green, blue (packed 00 01 10 xx).
  const std::string plte = chunk("PLTE", std::string("\xff\x00\x00\x00\xff\x00\x00\x00\xff", 9));
  write_bytes(dir / "pal.png", make_png(3, 1, 2, 3, {std::string(1, char(0x18))}, plte));
  const Image pal = proctex::load_image(dir / "pal.png");
  EXPECT_EQ(pal.pixel(0, 0)[0], 1.0f);
  EXPECT_EQ(pal.pixel(0, 0)[1], 0.0f);
  EXPECT_EQ(pal.pixel(1, 0)[1], 1.0f);
  EXPECT_EQ(pal.pixel(2, 0)[2], 1.0f);
  EXPECT_EQ(pal.pixel(2, 0)[0], 0.0f);
  // 1-bit grey, 8 pixels 10110000: white, black, white, white, black...
  write_bytes(dir / "bits.png", make_png(8, 1, 1, 0, {std::string(1, char(0xb0))}));
  const Image bits = proctex::load_image(dir / "bits.png");
  const float expect[8] = {1, 0, 1, 1, 0, 0, 0, 0};
  for (int x = 0; x < 8; ++x) {
    for (int c = 0; c < 3; ++c) EXPECT_EQ(bits.pixel(x, 0)[c], expect[x]) << x;
  }
}

TEST(PngCodec, CorruptAndTruncatedFilesAreClearErrors) {
  const bool loaded_before = proctex::image_backend_loaded();
  TempDir dir;
  std::string bytes = read_bytes(kTextures / "brick.png");
  std::string corrupt = bytes;
  for (size_t i = 100; i < corrupt.size() - 100; i += 7) corrupt[i] = char(corrupt[i] ^ 0x5a);
  write_bytes(dir / "corrupt.png", corrupt);
  std::string m = error_of([&] { proctex::load_image(dir / "corrupt.png"); });
  EXPECT_NE(m.find("corrupt.png"), std::string::npos) << m;
  EXPECT_NE(m.find("corrupt PNG"), std::string::npos) << m;
  write_bytes(dir / "cut.png", bytes.substr(0, bytes.size() / 2));
  m = error_of([&] { proctex::read_channels(dir / "cut.png"); });
  EXPECT_NE(m.find("cut.png"), std::string::npos) << m;
  EXPECT_NE(m.find("truncated PNG"), std::string::npos) << m;
  // Whole image data but no IEND: still incomplete.
  write_bytes(dir / "noend.png", bytes.substr(0, bytes.size() - 12));
  m = error_of([&] { proctex::load_image(dir / "noend.png"); });
  EXPECT_NE(m.find("truncated PNG"), std::string::npos) << m;
  // Nothing of a failed load reaches the module: PNG errors are ours.
  if (!loaded_before) {
    EXPECT_FALSE(proctex::image_backend_loaded());
  }
}

TEST(JpegCodec, TruncatedAndCorruptJpegsAreClearErrorsAndReadChannelsMatchesLoad) {
  TempDir dir;
  const std::string bytes = read_bytes(kTextures / "hubble_deep_field.jpg");
  write_bytes(dir / "cut.jpg", bytes.substr(0, bytes.size() / 2));
  std::string m = error_of([&] { proctex::load_image(dir / "cut.jpg"); });
  EXPECT_NE(m.find("cut.jpg"), std::string::npos) << m;
  EXPECT_NE(m.find("truncated JPEG"), std::string::npos) << m;
  write_bytes(dir / "head.jpg", bytes.substr(0, 300));
  m = error_of([&] { proctex::read_channels(dir / "head.jpg"); });
  EXPECT_NE(m.find("JPEG"), std::string::npos) << m;
  // The same decoder behind both calls: read_channels' code / 255 linearises to load_image's pixel.
  const Image img = proctex::load_image(kTextures / "hubble_deep_field.jpg");
  const ChannelImage raw = proctex::read_channels(kTextures / "hubble_deep_field.jpg");
  ASSERT_EQ(raw.width, img.width);
  ASSERT_EQ(raw.channels, 3);
  for (size_t i = 0; i < img.pixels.size(); i += 997) {
    ASSERT_FLOAT_EQ(img.pixels[i], proctex::srgb_to_linear(std::round(raw.data[i] * 255) / 255)) << i;
  }
}

TEST(PngCodec, HugeHeaderIsRefusedBeforeAllocatingInFilesAndMemory) {
  TempDir dir;
  const std::string bomb = make_png(60000, 60000, 16, 6, {});  // 60000^2 RGBA16: 29 GB as float
  write_bytes(dir / "bomb.png", bomb);
  for (const std::string& m :
       {error_of([&] { proctex::read_channels(dir / "bomb.png"); }),
        error_of([&] { proctex::decode_png({reinterpret_cast<const unsigned char*>(bomb.data()), bomb.size()}); })}) {
    EXPECT_NE(m.find("60000x60000"), std::string::npos) << m;
    EXPECT_NE(m.find("exceeds"), std::string::npos) << m;
  }
}

TEST(PngCodec, InMemoryRoundTripAndGarbage) {
  std::vector<uint8_t> codes(9 * 5 * 3);
  for (size_t i = 0; i < codes.size(); ++i) codes[i] = uint8_t(i * 13);
  const std::vector<unsigned char> png = proctex::encode_png(9, 5, 3, codes);
  ASSERT_GT(png.size(), 8u);
  const ChannelImage back = proctex::decode_png(png);
  ASSERT_EQ(back.width, 9);
  ASSERT_EQ(back.channels, 3);
  for (size_t i = 0; i < codes.size(); ++i) ASSERT_EQ(std::lround(back.data[i] * 255), codes[i]);
  const std::vector<unsigned char> half(png.begin(), png.begin() + png.size() / 2);
  EXPECT_NE(error_of([&] { proctex::decode_png(half); }).find("truncated PNG"), std::string::npos);
  const std::vector<unsigned char> junk(100, 0x42);
  EXPECT_NE(error_of([&] { proctex::decode_png(junk); }).find("PNG"), std::string::npos);
}

TEST(PngCodec, WritesThatPngCannotHoldAreRefused) {
  TempDir dir;
  WriteOptions o;
  o.file_type = PixelType::Float;
  const std::vector<float> px(3 * 4, 0.5f);
  const std::string m = error_of([&] { proctex::write_channels(dir / "f.png", 2, 2, o, PixelType::Float, px.data()); });
  EXPECT_NE(m.find("8 or 16 bits"), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(dir / "f.png"));
}

// --- The OpenImageIO module, loaded on first use.
TEST(ImageBackend, MultiChannelFloatExrRoundTripLoadsTheModule) {
  TempDir dir;
  const int w = 7, h = 5, n = 6;
  std::vector<float> data(size_t(w) * h * n);
  for (size_t i = 0; i < data.size(); ++i) data[i] = float(i) * 0.37f - 3.0f;  // negative, > 1: float only
  WriteOptions o;
  o.channels = n;
  o.file_type = PixelType::Float;
  o.channel_names = {"R", "G", "B", "N.X", "N.Y", "N.Z"};
  o.compression = "zip";
  proctex::write_channels(dir / "six.exr", w, h, o, PixelType::Float, data.data());
  EXPECT_TRUE(proctex::image_backend_loaded());
  const ChannelImage back = proctex::read_channels(dir / "six.exr");
  ASSERT_EQ(back.channels, n);
  EXPECT_EQ(back.file_type, PixelType::Float);
  // OpenEXR may store channels in its own order; the names say which is which.
  for (int c = 0; c < n; ++c) {
    const auto at = std::find(back.channel_names.begin(), back.channel_names.end(), o.channel_names[size_t(c)]);
    ASSERT_NE(at, back.channel_names.end()) << o.channel_names[size_t(c)];
    const size_t k = size_t(at - back.channel_names.begin());
    for (size_t p = 0; p < size_t(w) * h; ++p) ASSERT_EQ(back.data[p * n + k], data[p * n + size_t(c)]);
  }
}

TEST(ImageBackend, ExrStripWriterEqualsTheWholeImage) {
  TempDir dir;
  const int w = 40, h = 33;
  std::vector<float> data(size_t(w) * h * 3);
  for (size_t i = 0; i < data.size(); ++i) data[i] = float(i % 977) / 64.0f;  // exact in half
  WriteOptions o;
  o.file_type = PixelType::Half;
  proctex::StripWriter writer(dir / "s.exr", w, h, o);
  for (int y0 = 0; y0 < h; y0 += 10)
    writer.write_rows(y0, std::min(10, h - y0), PixelType::Float, data.data() + size_t(y0) * w * 3);
  writer.finish();
  const Image img = proctex::load_image(dir / "s.exr");
  for (size_t i = 0; i < data.size(); ++i) ASSERT_EQ(img.pixels[i], data[i]) << i;
}

TEST(ImageBackend, TheBinaryDoesNotLinkOpenImageIo) {
  // The dynamic loader's list of what the binary needs at start-up (what `ldd` prints).
  TempDir dir;
  const std::string cmd = std::string("LD_TRACE_LOADED_OBJECTS=1 '") + PROCTEX_BINARY + "' > '" +
                          (dir / "libs.txt").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string libs = read_bytes(dir / "libs.txt");
  EXPECT_NE(libs.find("libOpenCL"), std::string::npos) << libs;  // the listing worked
  EXPECT_EQ(libs.find("OpenImageIO"), std::string::npos) << libs;
  EXPECT_EQ(libs.find("libopencv"), std::string::npos) << libs;
}

TEST(ImageBackend, TheBinaryWritesExrAndAMissingModuleIsOneClearError) {
  TempDir dir;
  auto r = proctex::testing::run_proctex("-q render stripes -o '" + (dir / "ok.exr").string() + "' --size 16",
                                         dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(proctex::load_image(dir / "ok.exr").width, 16);
  r = proctex::testing::run_proctex("-q render stripes -o '" + (dir / "no.png").string() + "' --size 16",
                                    dir.path());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  setenv("PROCTEX_IMAGE_BACKEND", (dir / "missing.so").c_str(), 1);
  r = proctex::testing::run_proctex("-q render stripes -o '" + (dir / "bad.exr").string() + "' --size 16",
                                    dir.path());
  unsetenv("PROCTEX_IMAGE_BACKEND");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
  EXPECT_EQ(proctex::testing::line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("bad.exr"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("missing.so"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "bad.exr"));
  for (const auto& e : fs::directory_iterator(dir.path()))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(ImageBackend, AnInstalledBinaryUsesTheModuleOfItsInstallLayout) {
  // bin/proctex + lib/proctex/proctex_image_oiio.so (what `cmake --install` lays out): the module
  // beside the install wins over the build tree's; LD_DEBUG=files names the object dlopen mapped.
  TempDir dir;
  fs::create_directories(dir / "bin");
  fs::create_directories(dir.path() / "lib" / "proctex");
  fs::copy_file(PROCTEX_BINARY, dir / "bin/proctex");
  fs::permissions(dir / "bin/proctex", fs::perms::owner_exec, fs::perm_options::add);
  const fs::path module = fs::path(PROCTEX_BINARY).parent_path().parent_path() / "image" / "proctex_image_oiio.so";
  ASSERT_TRUE(fs::exists(module)) << module;
  fs::copy_file(module, dir.path() / "lib" / "proctex" / "proctex_image_oiio.so");
  const std::string cmd = "LD_DEBUG=files '" + (dir / "bin/proctex").string() + "' -q render stripes -o '" +
                          (dir / "x.exr").string() + "' --size 8 2>'" + (dir / "ld.txt").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << read_bytes(dir / "ld.txt");
  const std::string ld = read_bytes(dir / "ld.txt");
  EXPECT_NE(ld.find("file=" + (dir.path() / "lib" / "proctex" / "proctex_image_oiio.so").string()),
            std::string::npos)
      << ld.substr(0, 2000);
  EXPECT_EQ(ld.find("file=" + module.string()), std::string::npos);
  EXPECT_EQ(proctex::load_image(dir / "x.exr").width, 8);
}
