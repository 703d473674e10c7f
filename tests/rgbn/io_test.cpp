// RGBN files, normal-map encodings in both conventions, height fields and integration.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include "core/error.h"
#include "support.h"

using namespace proctex::rgbn;
using namespace rgbn_test;
namespace fs = std::filesystem;

namespace {

Rgbn random_normals(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0, 1);
  Rgbn r(w, h);
  for (size_t i = 0; i < r.size(); ++i) {
    float* n = &r.normal[3 * i];
    do {
      n[0] = g(rng), n[1] = g(rng), n[2] = std::abs(g(rng));
      const float l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      n[0] /= l, n[1] /= l, n[2] /= l;
    } while (n[2] < 0.05f);
    for (int c = 0; c < 3; ++c) r.albedo[3 * i + c] = std::uniform_real_distribution<float>(0, 1)(rng);
  }
  return r;
}

std::vector<uint8_t> read_bytes8(const fs::path& p) {
  auto in = OIIO::ImageInput::open(p.string());
  EXPECT_TRUE(in);
  std::vector<uint8_t> d(size_t(in->spec().width) * in->spec().height * in->spec().nchannels);
  in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::UINT8, d.data());
  return d;
}

}  // namespace

TEST(RgbnIo, ExrRoundTripIsExact) {
  TempDir dir("exr");
  const Rgbn a = random_normals(17, 9, 1);
  save_rgbn(a, dir.path / "a.exr");
  const Rgbn b = load_rgbn(dir.path / "a.exr");
  ASSERT_EQ(b.width, 17);
  ASSERT_EQ(b.height, 9);
  EXPECT_EQ(a.albedo, b.albedo);
  EXPECT_LT(max_angle(a, b), 1e-3);
  EXPECT_LT(max_norm_error(b), 1e-6);
}

TEST(RgbnIo, NormalMapRoundTripsInBothConventions) {
  TempDir dir("maps");
  const Rgbn a = random_normals(32, 16, 2);
  struct Case {
    std::string ext;
    int bits;
    double tolerance_deg;
  };
  // 8-bit: one code is 1/127.5 per component, at most ~0.4 degrees; 16-bit 256x finer; EXR float.
  for (const Case& c : {Case{".png", 8, 0.5}, Case{".png", 16, 0.01}, Case{".tif", 8, 0.5}, Case{".tif", 16, 0.01},
                        Case{".exr", 32, 1e-4}})
    for (Convention conv : {Convention::OpenGL, Convention::DirectX}) {
      const fs::path p = dir.path / ("m" + std::to_string(c.bits) + convention_name(conv) + c.ext);
      save_normal_map(a, p, conv, c.bits == 32 ? 8 : c.bits);
      const Rgbn b = load_normal_map(p, conv);
      EXPECT_LT(max_angle(a, b), c.tolerance_deg) << p;
      EXPECT_LT(max_norm_error(b), 1e-6);
      // Reading with the other convention mirrors y: a wrong convention is visible, not silent.
      const Rgbn wrong = load_normal_map(p, conv == Convention::OpenGL ? Convention::DirectX : Convention::OpenGL);
      for (size_t i = 0; i < a.size(); i += 37) EXPECT_NEAR(wrong.normal[3 * i + 1], -b.normal[3 * i + 1], 1e-6);
      // A second encode of the decoded (renormalised) map moves no code by more than one step.
      if (c.bits == 8) {
        save_normal_map(b, dir.path / ("again" + c.ext), conv, 8);
        const auto first = read_bytes8(p), second = read_bytes8(dir.path / ("again" + c.ext));
        ASSERT_EQ(first.size(), second.size());
        for (size_t i = 0; i < first.size(); ++i) EXPECT_LE(std::abs(int(first[i]) - int(second[i])), 1);
      }
    }
}

TEST(RgbnIo, FlatNormalIs128_128_255AndConventionsDifferInGreen) {
  TempDir dir("flat");
  Rgbn r(2, 1);
  const float s = std::sqrt(0.5f);
  r.n(1, 0)[0] = 0, r.n(1, 0)[1] = s, r.n(1, 0)[2] = s;  // tilted up (+Y)
  save_normal_map(r, dir.path / "gl.png", Convention::OpenGL);
  save_normal_map(r, dir.path / "dx.png", Convention::DirectX);
  const auto gl = read_bytes8(dir.path / "gl.png"), dx = read_bytes8(dir.path / "dx.png");
  EXPECT_EQ(gl[0], 128);
  EXPECT_EQ(gl[1], 128);
  EXPECT_EQ(gl[2], 255);
  EXPECT_EQ(gl[4], uint8_t(std::round((s + 1) * 127.5)));  // green up in OpenGL
  EXPECT_EQ(dx[4], uint8_t(std::round((1 - s) * 127.5)));  // green down in DirectX
}

TEST(RgbnIo, BadFilesFailWithOneClearErrorAndNoOutput) {
  TempDir dir("bad");
  // Non-unit normals in an RGBN file.
  {
    OIIO::ImageSpec spec(2, 2, 6, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"R", "G", "B", "N.X", "N.Y", "N.Z"};
    std::vector<float> d(24, 0.5f);
    auto out = OIIO::ImageOutput::create((dir.path / "nonunit.exr").string());
    out->open((dir.path / "nonunit.exr").string(), spec);
    out->write_image(OIIO::TypeDesc::FLOAT, d.data());
    out->close();
    EXPECT_THROW(load_rgbn(dir.path / "nonunit.exr"), proctex::Error);
    d[3] = std::nanf("");
    auto out2 = OIIO::ImageOutput::create((dir.path / "nan.exr").string());
    out2->open((dir.path / "nan.exr").string(), spec);
    out2->write_image(OIIO::TypeDesc::FLOAT, d.data());
    out2->close();
    EXPECT_THROW(load_rgbn(dir.path / "nan.exr"), proctex::Error);
  }
  // A plain image is not an RGBN.
  save_normal_map(Rgbn(4, 4), dir.path / "map.exr", Convention::OpenGL);
  EXPECT_THROW(load_rgbn(dir.path / "map.exr"), proctex::Error);
  EXPECT_THROW(parse_convention("opengl-ish"), proctex::UsageError);
  // A black PNG is not a normal map (zero-length normals after decoding).
  {
    std::vector<uint8_t> d(4 * 4 * 3, 127);
    OIIO::ImageSpec spec(4, 4, 3, OIIO::TypeDesc::UINT8);
    auto out = OIIO::ImageOutput::create((dir.path / "grey.png").string());
    out->open((dir.path / "grey.png").string(), spec);
    out->write_image(OIIO::TypeDesc::UINT8, d.data());
    out->close();
    EXPECT_THROW(load_normal_map(dir.path / "grey.png", Convention::OpenGL), proctex::Error);
  }
  // A failed write leaves nothing behind.
  EXPECT_THROW(save_rgbn(Rgbn(4, 4), dir.path / "missing" / "x.exr"), proctex::Error);
  EXPECT_FALSE(fs::exists(dir.path / "missing"));
  size_t files = 0;
  for (auto& e : fs::directory_iterator(dir.path)) files += e.path().filename().string().find(".tmp") != std::string::npos;
  EXPECT_EQ(files, 0u);
}

TEST(RgbnHeight, NormalsOfAHeightFieldIntegrateBackPeriodic) {
  const HeightField z = periodic_field(64, 48, 3);
  const Rgbn n = from_height(z, 1.0f, true);
  EXPECT_LT(max_norm_error(n), 1e-6);
  EXPECT_LT(integrability_error(n), 1e-4);
  const Integration r = to_height(n, true);
  double mean = 0;
  for (float v : z.z) mean += v;
  mean /= double(z.z.size());
  double err = 0, range = 0;
  for (size_t i = 0; i < z.z.size(); ++i) {
    err = std::max(err, std::abs((z.z[i] - mean) - r.z.z[i]));
    range = std::max(range, std::abs(z.z[i] - mean));
  }
  EXPECT_LT(err, 0.01 * range) << "max error " << err << " of range " << range;
  EXPECT_LT(r.residual, 1e-2);
}

TEST(RgbnHeight, NonPeriodicRampIntegratesWithoutWrapArtefacts) {
  HeightField z{40, 30, std::vector<float>(1200)};
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) z.at(x, y) = 0.4f * x - 0.25f * y + 0.01f * x * y;  // y counts rows (down)
  const Rgbn n = from_height(z, 1.0f, false);
  const Integration r = to_height(n, false);
  // Compare after removing the mean, in the interior.
  double mz = 0, mr = 0;
  for (size_t i = 0; i < z.z.size(); ++i) mz += z.z[i], mr += r.z.z[i];
  mz /= 1200, mr /= 1200;
  double worst = 0;
  for (int y = 2; y < 28; ++y)
    for (int x = 2; x < 38; ++x) worst = std::max(worst, double(std::abs((z.at(x, y) - mz) - (r.z.at(x, y) - mr))));
  const double range = 0.4 * 40 + 0.25 * 30 + 0.01 * 40 * 30;
  EXPECT_LT(worst, 0.03 * range);
  // Periodic integration of the same non-tileable field wraps the ramp around: much worse.
  const Integration p = to_height(n, true);
  double mp = 0, worst_p = 0;
  for (float v : p.z.z) mp += v;
  mp /= 1200;
  for (int y = 2; y < 28; ++y)
    for (int x = 2; x < 38; ++x) worst_p = std::max(worst_p, double(std::abs((z.at(x, y) - mz) - (p.z.at(x, y) - mp))));
  EXPECT_GT(worst_p, 3 * worst);
}

TEST(RgbnHeight, TileableHeightGivesSeamlessNormals) {
  const HeightField z = periodic_field(32, 32, 4);
  const Rgbn wrap = from_height(z, 2.0f, true), clamp = from_height(z, 2.0f, false);
  // Interior identical, edges differ only where the clamped version uses one-sided differences.
  EXPECT_LT(angle_deg(wrap.n(10, 10), clamp.n(10, 10)), 1e-4);
  // Periodic normals at x = 0 use the neighbour across the seam: same as a shifted field's interior.
  HeightField shifted = z;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) shifted.at(x, y) = z.at((x + 16) % 32, y);
  const Rgbn s = from_height(shifted, 2.0f, false);
  EXPECT_LT(angle_deg(wrap.n(0, 10), s.n(16, 10)), 1e-4);
}
