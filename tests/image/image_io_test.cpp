// load_image / save_image: round trips, the shared photos, and every failure path we can provoke.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <random>
#include <string>
#include <unistd.h>
#include <vector>

#include "core/error.h"
#include "image/image.h"

namespace fs = std::filesystem;
using proctex::Error;
using proctex::Image;

namespace {

const fs::path kTextures = fs::path(PROCTEX_SHARED_DIR) / "textures";

// A fresh directory per test, removed afterwards.
class ImageIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("proctex-image-" + std::to_string(getpid()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(dir_, ec);
  }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
    return names;
  }
  fs::path dir_;
};

// Smooth ramps in each channel, spanning [0, 1] linear.
Image gradient(int w, int h) {
  Image image(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float* p = image.pixel(x, y);
      p[0] = float(x) / (w - 1);
      p[1] = float(y) / (h - 1);
      p[2] = float((x * 7 + y * 13) % 101) / 100.0f;
    }
  }
  return image;
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// --- A minimal PNG writer (stored, uncompressed deflate), so tests can craft files that
// save_image never produces: grey+alpha, 16-bit grey, and headers with absurd sizes.
uint32_t crc32(const std::string& data) {
  uint32_t crc = 0xffffffffu;
  for (unsigned char c : data) {
    crc ^= c;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

std::string be32(uint32_t v) {
  return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
  return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}

std::string zlib_stored(const std::string& raw) {
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  std::string out = "\x78\x01";
  for (size_t pos = 0; pos == 0 || pos < raw.size(); pos += 65535) {
    const size_t n = std::min<size_t>(65535, raw.size() - pos);
    const bool last = pos + n >= raw.size();
    out += char(last ? 1 : 0);
    out += {char(n & 0xff), char(n >> 8), char(~n & 0xff), char((~n >> 8) & 0xff)};
    out += raw.substr(pos, n);
  }
  return out + be32((b << 16) | a);
}

// colour_type 0 = grey, 4 = grey+alpha; `rows` are the raw scanlines without filter bytes.
std::string make_png(uint32_t w, uint32_t h, int bit_depth, int colour_type,
                     const std::vector<std::string>& rows) {
  std::string ihdr = be32(w) + be32(h) + char(bit_depth) + char(colour_type) + '\0' + '\0' + '\0';
  std::string raw;
  for (const auto& row : rows) raw += '\0' + row;
  std::string png = "\x89PNG\r\n\x1a\n";
  png += png_chunk("IHDR", ihdr);
  png += png_chunk("IDAT", zlib_stored(raw));
  return png + png_chunk("IEND", "");
}

// Loads and expects an Error; returns its message. Also checks that OIIO printed nothing.
std::string load_error(const fs::path& path, const proctex::ImageLimits& limits = {}) {
  ::testing::internal::CaptureStderr();
  std::string message = "(no error)";
  try {
    proctex::load_image(path, limits);
  } catch (const Error& e) {
    message = e.message();
    EXPECT_FALSE(e.hint().empty());
  }
  const std::string stderr_text = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(stderr_text, "") << "library printed to stderr while loading " << path;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "error message is not one line";
  return message;
}

float max_srgb_difference(const Image& a, const Image& b) {
  float worst = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    worst = std::max(worst, std::abs(proctex::linear_to_srgb(a.pixels[i]) -
                                      proctex::linear_to_srgb(b.pixels[i])));
  }
  return worst;
}

}  // namespace

TEST_F(ImageIoTest, PngRoundTripWithinEightBitQuantisation) {
  const Image original = gradient(67, 41);
  proctex::save_image(original, dir_ / "g.png");
  const Image loaded = proctex::load_image(dir_ / "g.png");
  ASSERT_EQ(loaded.width, 67);
  ASSERT_EQ(loaded.height, 41);
  // Rounding to the nearest of 255 sRGB steps is off by at most half a step.
  EXPECT_LE(max_srgb_difference(original, loaded), 0.5f / 255.0f + 1e-5f);
  EXPECT_GT(max_srgb_difference(original, loaded), 0.0f);  // it really was quantised
}

TEST_F(ImageIoTest, PngStoresSrgbCodesNotLinearValues) {
  // Linear value of sRGB code 128 must come back exactly (code 128 in the file).
  const float mid = proctex::srgb_to_linear(128.0f / 255.0f);
  proctex::save_image(Image(4, 4, mid), dir_ / "mid.png");
  const Image loaded = proctex::load_image(dir_ / "mid.png");
  for (float v : loaded.pixels) EXPECT_FLOAT_EQ(v, mid);
}

TEST_F(ImageIoTest, PngClampsOutOfRangeValues) {
  Image image(2, 1);
  image.pixel(0, 0)[0] = -3.0f;
  image.pixel(1, 0)[0] = 7.0f;
  image.pixel(1, 0)[1] = std::nanf("");
  proctex::save_image(image, dir_ / "clamp.png");
  const Image loaded = proctex::load_image(dir_ / "clamp.png");
  EXPECT_EQ(loaded.pixel(0, 0)[0], 0.0f);
  EXPECT_EQ(loaded.pixel(1, 0)[0], 1.0f);
  EXPECT_EQ(loaded.pixel(1, 0)[1], 0.0f);
}

TEST_F(ImageIoTest, ExrRoundTripWithinHalfPrecision) {
  Image original = gradient(33, 20);
  original.pixel(3, 4)[0] = 17.25f;  // linear HDR values survive, unlike in PNG
  original.pixel(5, 6)[2] = 0.001f;
  proctex::save_image(original, dir_ / "g.exr");
  const Image loaded = proctex::load_image(dir_ / "g.exr");
  ASSERT_EQ(loaded.width, 33);
  ASSERT_EQ(loaded.height, 20);
  for (size_t i = 0; i < original.pixels.size(); ++i) {
    const float a = original.pixels[i], b = loaded.pixels[i];
    EXPECT_NEAR(a, b, std::abs(a) / 1024.0f + 1e-7f) << "index " << i;
  }
  EXPECT_NEAR(loaded.pixel(3, 4)[0], 17.25f, 1e-6f);
}

TEST_F(ImageIoTest, TiffRoundTripWithinSixteenBitQuantisation) {
  const Image original = gradient(50, 30);
  proctex::save_image(original, dir_ / "g.tif");
  const Image loaded = proctex::load_image(dir_ / "g.tif");
  ASSERT_EQ(loaded.width, 50);
  EXPECT_LE(max_srgb_difference(original, loaded), 0.5f / 65535.0f + 2e-6f);
}

TEST_F(ImageIoTest, JpegRoundTripIsClose) {
  // Gentle ramps in sRGB space: JPEG (quality 95, 4:2:0 chroma) is lossy, but only slightly here.
  Image original(64, 64);
  for (int y = 0; y < 64; ++y) {
    for (int x = 0; x < 64; ++x) {
      float* p = original.pixel(x, y);
      p[0] = proctex::srgb_to_linear(0.2f + 0.6f * x / 63.0f);
      p[1] = proctex::srgb_to_linear(0.3f + 0.4f * y / 63.0f);
      p[2] = proctex::srgb_to_linear(0.5f);
    }
  }
  proctex::save_image(original, dir_ / "g.jpg");
  const Image loaded = proctex::load_image(dir_ / "g.jpg");
  ASSERT_EQ(loaded.width, 64);
  ASSERT_EQ(loaded.height, 64);
  double total = 0;
  for (size_t i = 0; i < original.pixels.size(); ++i) {
    total += std::abs(proctex::linear_to_srgb(original.pixels[i]) -
                      proctex::linear_to_srgb(loaded.pixels[i]));
  }
  EXPECT_LT(total / original.pixels.size(), 1.0 / 255.0);
  EXPECT_LT(max_srgb_difference(original, loaded), 4.0f / 255.0f);
}

TEST_F(ImageIoTest, UppercaseExtensionIsAccepted) {
  proctex::save_image(gradient(8, 8), dir_ / "UP.PNG");
  EXPECT_EQ(proctex::load_image(dir_ / "UP.PNG").width, 8);
}

TEST_F(ImageIoTest, SaveOverwritesAndLeavesNoTemporaryFiles) {
  proctex::save_image(Image(8, 8, 0.0f), dir_ / "a.png");
  proctex::save_image(Image(8, 8, 1.0f), dir_ / "a.png");
  EXPECT_EQ(entries(), std::vector<std::string>{"a.png"});
  EXPECT_EQ(proctex::load_image(dir_ / "a.png").pixels[0], 1.0f);
}

TEST(ImageLoad, BrickIsGreyExpandedToEqualChannels) {
  const Image brick = proctex::load_image(kTextures / "brick.png");
  ASSERT_EQ(brick.width, 512);
  ASSERT_EQ(brick.height, 512);
  ASSERT_EQ(brick.pixels.size(), 512u * 512u * 3u);
  float lo = 1, hi = 0;
  for (size_t i = 0; i < brick.pixels.size(); i += 3) {
    ASSERT_EQ(brick.pixels[i], brick.pixels[i + 1]);
    ASSERT_EQ(brick.pixels[i], brick.pixels[i + 2]);
    lo = std::min(lo, brick.pixels[i]);
    hi = std::max(hi, brick.pixels[i]);
  }
  EXPECT_GE(lo, 0.0f);
  EXPECT_LE(hi, 1.0f);
  EXPECT_GT(hi - lo, 0.3f);  // a real photo, not a blank
}

TEST(ImageLoad, HubbleIsColourAndLinearised) {
  const Image hubble = proctex::load_image(kTextures / "hubble_deep_field.jpg");
  ASSERT_EQ(hubble.width, 1000);
  ASSERT_EQ(hubble.height, 872);
  bool coloured = false;
  double sum = 0;
  for (size_t i = 0; i < hubble.pixels.size(); i += 3) {
    coloured |= std::abs(hubble.pixels[i] - hubble.pixels[i + 2]) > 0.05f;
    sum += hubble.pixels[i];
  }
  EXPECT_TRUE(coloured);
  // Mostly black sky: linear values are small, and every value is a linearised 8-bit code.
  EXPECT_LT(sum / (hubble.pixels.size() / 3), 0.2);
  const float v = hubble.pixels[12345];
  EXPECT_FLOAT_EQ(v, proctex::srgb_to_linear(std::round(proctex::linear_to_srgb(v) * 255) / 255));
}

TEST_F(ImageIoTest, GreyAlphaPngDropsAlpha) {
  // 2x1 grey+alpha: (grey 128, alpha 0), (grey 255, alpha 77).
  write_bytes(dir_ / "ga.png", make_png(2, 1, 8, 4, {std::string("\x80\x00\xff\x4d", 4)}));
  const Image image = proctex::load_image(dir_ / "ga.png");
  ASSERT_EQ(image.width, 2);
  ASSERT_EQ(image.height, 1);
  const float mid = proctex::srgb_to_linear(128.0f / 255.0f);
  for (int c = 0; c < 3; ++c) {
    EXPECT_FLOAT_EQ(image.pixel(0, 0)[c], mid);  // not premultiplied by alpha 0
    EXPECT_FLOAT_EQ(image.pixel(1, 0)[c], 1.0f);
  }
}

TEST_F(ImageIoTest, SixteenBitGreyIsLinearisedWithFullPrecision) {
  const uint16_t code = 30000;
  write_bytes(dir_ / "g16.png",
              make_png(1, 1, 16, 0, {std::string{char(code >> 8), char(code & 0xff)}}));
  const Image image = proctex::load_image(dir_ / "g16.png");
  EXPECT_NEAR(image.pixels[0], proctex::srgb_to_linear(code / 65535.0f), 1e-6f);
  EXPECT_EQ(image.pixels[0], image.pixels[2]);
}

TEST_F(ImageIoTest, HugeHeaderIsRejectedBeforeReadingPixels) {
  // A valid IHDR claiming 100000x100000 and an empty IDAT: only the header check can produce the
  // "exceeds" message; reading pixels would fail differently (or first allocate 120 GB).
  write_bytes(dir_ / "bomb.png", make_png(100000, 100000, 8, 0, {}));
  const std::string message = load_error(dir_ / "bomb.png");
  EXPECT_NE(message.find("100000x100000"), std::string::npos) << message;
  EXPECT_NE(message.find("exceeds"), std::string::npos) << message;
  EXPECT_NE(message.find("bomb.png"), std::string::npos) << message;
}

TEST(ImageLoad, CustomLimitsRejectTheSharedPhoto) {
  proctex::ImageLimits limits;
  limits.max_dimension = 100;
  const std::string message = load_error(kTextures / "brick.png", limits);
  EXPECT_NE(message.find("exceeds"), std::string::npos) << message;
  limits = {};
  limits.max_pixels = 512 * 512 - 1;
  EXPECT_NE(load_error(kTextures / "brick.png", limits).find("exceeds"), std::string::npos);
}

TEST_F(ImageIoTest, MissingFileErrorNamesThePath) {
  const std::string message = load_error(dir_ / "no-such-photo.png");
  EXPECT_NE(message.find((dir_ / "no-such-photo.png").string()), std::string::npos) << message;
  EXPECT_NE(message.find("not found"), std::string::npos) << message;
}

TEST_F(ImageIoTest, DirectoryIsNotAnImage) {
  EXPECT_NE(load_error(dir_).find("not a regular file"), std::string::npos);
}

TEST_F(ImageIoTest, TruncatedPngIsAnError) {
  const std::string bytes = read_bytes(kTextures / "brick.png");
  for (size_t keep : {bytes.size() / 2, bytes.size() - 20, size_t(40)}) {
    write_bytes(dir_ / "cut.png", bytes.substr(0, keep));
    const std::string message = load_error(dir_ / "cut.png");
    EXPECT_NE(message.find("cut.png"), std::string::npos) << "kept " << keep << ": " << message;
  }
}

TEST_F(ImageIoTest, TruncatedJpegIsAnError) {
  const std::string bytes = read_bytes(kTextures / "hubble_deep_field.jpg");
  for (size_t keep : {bytes.size() / 2, bytes.size() - 100, size_t(300)}) {
    write_bytes(dir_ / "cut.jpg", bytes.substr(0, keep));
    const std::string message = load_error(dir_ / "cut.jpg");
    EXPECT_NE(message.find("cut.jpg"), std::string::npos) << "kept " << keep << ": " << message;
  }
}

TEST_F(ImageIoTest, TruncatedExrIsAnError) {
  proctex::save_image(gradient(200, 100), dir_ / "whole.exr");
  const std::string bytes = read_bytes(dir_ / "whole.exr");
  write_bytes(dir_ / "cut.exr", bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(load_error(dir_ / "cut.exr").find("cut.exr"), std::string::npos);
}

TEST_F(ImageIoTest, TruncatedTiffIsAnError) {
  proctex::save_image(gradient(200, 100), dir_ / "whole.tif");
  const std::string bytes = read_bytes(dir_ / "whole.tif");
  write_bytes(dir_ / "cut.tif", bytes.substr(0, bytes.size() / 2));
  EXPECT_NE(load_error(dir_ / "cut.tif").find("cut.tif"), std::string::npos);
}

TEST_F(ImageIoTest, CorruptPngDataIsAnError) {
  // Valid signature and header, garbage where the compressed pixels are.
  std::string bytes = read_bytes(kTextures / "brick.png");
  for (size_t i = 100; i < bytes.size() - 100; i += 7) bytes[i] = char(bytes[i] ^ 0x5a);
  write_bytes(dir_ / "corrupt.png", bytes);
  EXPECT_NE(load_error(dir_ / "corrupt.png").find("corrupt.png"), std::string::npos);
}

TEST_F(ImageIoTest, RandomBytesAreAnError) {
  std::mt19937 rng(42);
  std::string bytes(4096, '\0');
  for (char& c : bytes) c = char(rng());
  for (const char* name : {"noise.png", "noise.jpg", "noise.exr", "noise.bin"}) {
    write_bytes(dir_ / name, bytes);
    EXPECT_NE(load_error(dir_ / name).find(name), std::string::npos);
  }
}

TEST_F(ImageIoTest, EmptyFileIsAnError) {
  write_bytes(dir_ / "empty.png", "");
  EXPECT_NE(load_error(dir_ / "empty.png").find("empty.png"), std::string::npos);
}

TEST_F(ImageIoTest, UnknownExtensionIsAnErrorAndCreatesNothing) {
  EXPECT_THROW(proctex::save_image(gradient(4, 4), dir_ / "out.bmpx"), Error);
  EXPECT_THROW(proctex::save_image(gradient(4, 4), dir_ / "noext"), Error);
  EXPECT_TRUE(entries().empty());
}

TEST_F(ImageIoTest, EmptyImageIsAnErrorAndCreatesNothing) {
  EXPECT_THROW(proctex::save_image(Image(), dir_ / "empty.png"), Error);
  Image broken(4, 4);
  broken.pixels.resize(5);  // inconsistent with 4x4
  EXPECT_THROW(proctex::save_image(broken, dir_ / "broken.png"), Error);
  EXPECT_TRUE(entries().empty());
}

TEST_F(ImageIoTest, SaveIntoMissingDirectoryIsAnError) {
  try {
    proctex::save_image(gradient(4, 4), dir_ / "missing" / "out.png");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("missing"), std::string::npos) << e.message();
  }
  EXPECT_TRUE(entries().empty());
}

TEST_F(ImageIoTest, SaveWhereParentIsAFileIsAnError) {
  // Unwritable even for root (tests may run as root, where chmod does not stop writes).
  write_bytes(dir_ / "file", "x");
  EXPECT_THROW(proctex::save_image(gradient(4, 4), dir_ / "file" / "out.png"), Error);
  EXPECT_EQ(entries(), std::vector<std::string>{"file"});
}

TEST_F(ImageIoTest, FailedRenameRemovesTheTemporaryFile) {
  // The target name is taken by a directory: writing succeeds, the final rename fails.
  fs::create_directory(dir_ / "out.png");
  try {
    proctex::save_image(gradient(4, 4), dir_ / "out.png");
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("out.png"), std::string::npos) << e.message();
    EXPECT_EQ(e.message().find("Success"), std::string::npos) << e.message();
  }
  EXPECT_EQ(entries(), std::vector<std::string>{"out.png"});
  EXPECT_TRUE(fs::is_empty(dir_ / "out.png"));
}

TEST_F(ImageIoTest, SaveIntoReadOnlyDirectoryIsAnErrorAndLeavesNoFile) {
  const fs::path locked = dir_ / "locked";
  fs::create_directory(locked);
  fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec);
  if (std::ofstream(locked / "probe")) {
    fs::remove(locked / "probe");
    GTEST_SKIP() << "running with privileges that ignore directory permissions";
  }
  for (const char* name : {"out.png", "out.exr", "out.tif", "out.jpg"}) {
    try {
      proctex::save_image(gradient(4, 4), locked / name);
      ADD_FAILURE() << "expected an Error for " << name;
    } catch (const Error& e) {
      EXPECT_NE(e.message().find(name), std::string::npos) << e.message();
    }
  }
  EXPECT_TRUE(fs::is_empty(locked));
}

TEST(ImageDimensions, CheckDimensions) {
  EXPECT_NO_THROW(proctex::check_dimensions(1, 1));
  EXPECT_NO_THROW(proctex::check_dimensions(65536, 4096));
  EXPECT_THROW(proctex::check_dimensions(0, 10), Error);
  EXPECT_THROW(proctex::check_dimensions(10, -1), Error);
  EXPECT_THROW(proctex::check_dimensions(65537, 1), Error);
  EXPECT_THROW(proctex::check_dimensions(65536, 65536), Error);  // 4 G pixels > 268 M
  proctex::ImageLimits small;
  small.max_dimension = 100;
  small.max_pixels = 5000;
  EXPECT_NO_THROW(proctex::check_dimensions(100, 50, small));
  EXPECT_THROW(proctex::check_dimensions(100, 51, small), Error);
  EXPECT_THROW(proctex::check_dimensions(101, 1, small), Error);
}
