// Pixel operations: sRGB curves, crop, resize, luminance, contact sheets.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numeric>
#include <random>

#include "core/error.h"
#include "image/image.h"

using proctex::Error;
using proctex::Image;

namespace {

Image noise(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Image image(w, h);
  for (float& v : image.pixels) v = u(rng);
  return image;
}

std::array<double, 3> channel_means(const Image& image) {
  std::array<double, 3> sum{0, 0, 0};
  for (size_t i = 0; i < image.pixels.size(); ++i) sum[i % 3] += image.pixels[i];
  for (double& s : sum) s /= double(image.width) * image.height;
  return sum;
}

// Pixel (x, y) of the image tagged so crops can be checked: r = x, g = y, b = constant.
Image coordinates(int w, int h) {
  Image image(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      image.pixel(x, y)[0] = float(x);
      image.pixel(x, y)[1] = float(y);
      image.pixel(x, y)[2] = 0.5f;
    }
  }
  return image;
}

}  // namespace

TEST(Srgb, KnownPoints) {
  EXPECT_EQ(proctex::linear_to_srgb(0.0f), 0.0f);
  EXPECT_EQ(proctex::srgb_to_linear(0.0f), 0.0f);
  EXPECT_NEAR(proctex::linear_to_srgb(1.0f), 1.0f, 1e-6f);
  EXPECT_NEAR(proctex::srgb_to_linear(1.0f), 1.0f, 1e-6f);
  // 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357; a 2.2 gamma would give 0.7297.
  EXPECT_NEAR(proctex::linear_to_srgb(0.5f), 0.735357f, 1e-5f);
  EXPECT_NEAR(proctex::srgb_to_linear(0.5f), 0.214041f, 1e-5f);
  // The linear toe below the threshold.
  EXPECT_NEAR(proctex::srgb_to_linear(0.02f), 0.02f / 12.92f, 1e-9f);
  EXPECT_NEAR(proctex::linear_to_srgb(0.001f), 0.01292f, 1e-8f);
}

TEST(Srgb, CurvesAreInversesAndMonotonic) {
  float previous = -1;
  for (int i = 0; i <= 1000; ++i) {
    const float v = i / 1000.0f;
    EXPECT_NEAR(proctex::linear_to_srgb(proctex::srgb_to_linear(v)), v, 2e-6f) << v;
    EXPECT_NEAR(proctex::srgb_to_linear(proctex::linear_to_srgb(v)), v, 2e-6f) << v;
    const float s = proctex::linear_to_srgb(v);
    EXPECT_GT(s, previous);
    previous = s;
  }
  // Continuous at the joint of the two pieces.
  EXPECT_NEAR(proctex::srgb_to_linear(0.04045f), proctex::srgb_to_linear(0.040451f), 1e-6f);
}

TEST(Luminance, Rec709Weights) {
  Image image(3, 1);
  image.pixel(0, 0)[0] = 1;
  image.pixel(1, 0)[1] = 1;
  image.pixel(2, 0)[0] = image.pixel(2, 0)[1] = image.pixel(2, 0)[2] = 0.5f;
  const std::vector<float> y = proctex::luminance(image);
  ASSERT_EQ(y.size(), 3u);
  EXPECT_FLOAT_EQ(y[0], 0.2126f);
  EXPECT_FLOAT_EQ(y[1], 0.7152f);
  EXPECT_FLOAT_EQ(y[2], 0.5f);
}

TEST(Crop, CopiesTheRectangle) {
  const Image out = proctex::crop(coordinates(10, 8), 3, 2, 4, 5);
  ASSERT_EQ(out.width, 4);
  ASSERT_EQ(out.height, 5);
  EXPECT_EQ(out.pixel(0, 0)[0], 3.0f);
  EXPECT_EQ(out.pixel(0, 0)[1], 2.0f);
  EXPECT_EQ(out.pixel(3, 4)[0], 6.0f);
  EXPECT_EQ(out.pixel(3, 4)[1], 6.0f);
  EXPECT_EQ(proctex::crop(coordinates(10, 8), 0, 0, 10, 8).pixels, coordinates(10, 8).pixels);
}

TEST(Crop, OutsideTheImageIsAnError) {
  const Image image = coordinates(10, 8);
  EXPECT_THROW(proctex::crop(image, -1, 0, 2, 2), Error);
  EXPECT_THROW(proctex::crop(image, 0, -1, 2, 2), Error);
  EXPECT_THROW(proctex::crop(image, 9, 0, 2, 2), Error);
  EXPECT_THROW(proctex::crop(image, 0, 7, 2, 2), Error);
  EXPECT_THROW(proctex::crop(image, 0, 0, 0, 2), Error);
  EXPECT_THROW(proctex::crop(image, 0, 0, 2, -3), Error);
  EXPECT_THROW(proctex::crop(image, 1, 1, 2147483647, 1), Error);  // no int overflow
  EXPECT_THROW(proctex::crop(Image(), 0, 0, 1, 1), Error);
}

TEST(Crop, CenterCropSquare) {
  const Image wide = proctex::center_crop_square(coordinates(10, 6));
  ASSERT_EQ(wide.width, 6);
  ASSERT_EQ(wide.height, 6);
  EXPECT_EQ(wide.pixel(0, 0)[0], 2.0f);
  const Image tall = proctex::center_crop_square(coordinates(5, 9));
  ASSERT_EQ(tall.width, 5);
  EXPECT_EQ(tall.pixel(0, 0)[1], 2.0f);
}

TEST(Resize, PreservesTheMeanForNonIntegerRatios) {
  const Image in = noise(512, 512, 1);
  const auto mean_in = channel_means(in);
  for (auto [w, h] : {std::pair{100, 100}, {317, 45}, {700, 1031}, {1, 1}, {512, 3}}) {
    const Image out = proctex::resize(in, w, h);
    ASSERT_EQ(out.width, w);
    ASSERT_EQ(out.height, h);
    const auto mean_out = channel_means(out);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean_out[c], mean_in[c], 2e-6) << w << "x" << h;
  }
}

TEST(Resize, ConstantStaysConstant) {
  const Image in(123, 77, 0.3f);
  for (auto [w, h] : {std::pair{50, 50}, {200, 31}, {7, 300}}) {
    for (float v : proctex::resize(in, w, h).pixels) ASSERT_NEAR(v, 0.3f, 1e-6f);
  }
}

TEST(Resize, ExactAreaWeights) {
  // 3 pixels -> 2: output 0 covers [0, 1.5): (a + 0.5 b) / 1.5; output 1 covers [1.5, 3).
  Image in(3, 1);
  in.pixel(0, 0)[0] = 3, in.pixel(1, 0)[0] = 6, in.pixel(2, 0)[0] = 9;
  const Image down = proctex::resize(in, 2, 1);
  EXPECT_FLOAT_EQ(down.pixel(0, 0)[0], (3 + 0.5f * 6) / 1.5f);
  EXPECT_FLOAT_EQ(down.pixel(1, 0)[0], (0.5f * 6 + 9) / 1.5f);
  // 2x2 box average.
  Image quad(2, 2);
  quad.pixel(0, 0)[1] = 1, quad.pixel(1, 0)[1] = 2, quad.pixel(0, 1)[1] = 3, quad.pixel(1, 1)[1] = 6;
  EXPECT_FLOAT_EQ(proctex::resize(quad, 1, 1).pixels[1], 3.0f);
  // Upsampling 2 -> 3: the middle output straddles both inputs equally.
  Image two(2, 1);
  two.pixel(0, 0)[2] = 0, two.pixel(1, 0)[2] = 1;
  const Image up = proctex::resize(two, 3, 1);
  EXPECT_FLOAT_EQ(up.pixel(0, 0)[2], 0.0f);
  EXPECT_FLOAT_EQ(up.pixel(1, 0)[2], 0.5f);
  EXPECT_FLOAT_EQ(up.pixel(2, 0)[2], 1.0f);
}

TEST(Resize, SameSizeIsACopyAndBadSizesAreErrors) {
  const Image in = noise(20, 10, 2);
  EXPECT_EQ(proctex::resize(in, 20, 10).pixels, in.pixels);
  EXPECT_THROW(proctex::resize(in, 0, 10), Error);
  EXPECT_THROW(proctex::resize(in, 10, -1), Error);
  EXPECT_THROW(proctex::resize(Image(), 10, 10), Error);
}

TEST(Resize, LargeImageIsFast) {
  const Image in(4096, 4096, 0.25f);
  const auto start = std::chrono::steady_clock::now();
  const Image out = proctex::resize(in, 1000, 1000);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_NEAR(out.pixel(500, 500)[0], 0.25f, 1e-6f);
  // Typically ~0.1 s; the loose bound only catches an accidentally quadratic filter.
  EXPECT_LT(seconds, 2.0);
}

TEST(ContactSheet, LayoutTilesAndLabels) {
  std::vector<Image> tiles;
  for (int i = 0; i < 5; ++i) tiles.push_back(Image(64, 64, 0.1f * (i + 1)));
  tiles[1] = Image(128, 80, 1.0f);  // resized (and cropped square) to 64x64
  const Image sheet =
      proctex::contact_sheet(tiles, {"one", "two", "three", "four", "five"}, 3, 64);
  // 3 columns x 2 rows; each cell is a tile plus a margin, each row also a label line.
  ASSERT_GT(sheet.width, 3 * 64);
  ASSERT_GT(sheet.height, 2 * 64);
  EXPECT_LT(sheet.width, 3 * 64 + 4 * 32);
  const int margin = (sheet.width - 3 * 64) / 4;
  EXPECT_EQ(sheet.width, 3 * 64 + 4 * margin);
  const int cell_h = (sheet.height - margin) / 2;
  EXPECT_EQ(sheet.height, 2 * cell_h + margin);
  EXPECT_GT(cell_h, 64 + margin);  // room for the label

  // Tile centres hold the tile values; the corner is the dark background.
  const float bg = sheet.pixel(0, 0)[0];
  EXPECT_LT(bg, 0.1f);
  EXPECT_FLOAT_EQ(sheet.pixel(margin + 32, margin + 32)[0], 0.1f);
  EXPECT_FLOAT_EQ(sheet.pixel(2 * margin + 64 + 32, margin + 32)[1], 1.0f);
  EXPECT_FLOAT_EQ(sheet.pixel(margin + 32, margin + cell_h + 32)[2], 0.4f);
  // The unused sixth cell is background.
  EXPECT_EQ(sheet.pixel(3 * margin + 128 + 32, margin + cell_h + 32)[0], bg);

  // The label strip under the first tile has bright text pixels (when a font is available).
  int bright = 0;
  for (int y = margin + 64; y < margin + cell_h; ++y) {
    for (int x = margin; x < margin + 64; ++x) bright += sheet.pixel(x, y)[0] > 0.4f;
  }
  EXPECT_GT(bright, 10) << "no label text rendered; is fonts-dejavu-core installed?";
}

TEST(ContactSheet, MissingLabelsAndBadArguments) {
  const std::vector<Image> tiles(3, Image(16, 16, 0.5f));
  EXPECT_NO_THROW(proctex::contact_sheet(tiles, {}, 2, 16));
  EXPECT_NO_THROW(proctex::contact_sheet(tiles, {"a very long label that cannot fit"}, 10, 16));
  EXPECT_THROW(proctex::contact_sheet({}, {}, 2, 16), Error);
  EXPECT_THROW(proctex::contact_sheet(tiles, {}, 0, 16), Error);
  EXPECT_THROW(proctex::contact_sheet(tiles, {}, 2, 0), Error);
}
