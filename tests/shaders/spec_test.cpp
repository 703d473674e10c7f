// Texture specs: parsing from the command line and JSON, and validation against a declaration.
#include <gtest/gtest.h>

#include <fstream>

#include "core/error.h"
#include "shaders/shader.h"
#include "shaders/spec.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

ShaderDecl sample_decl() {
  return parse_shader("shaders/test/sample.cl", R"(// @shader "x"
// @param float size = 0.25 [0.01, 1] log "Feature size"
// @param int   count = 4 [1, 12] "How many"
// @param color tint = (0.5, 0.25, 1) "Tint"
// @param enum  mode = wavy {flat, wavy, rough} "Mode"
// @param bool  flip = true "Mirror it"
float3 shade(float2 p, float fw, uint seed, const Params P) { return P.tint; }
)");
}

TEST(Spec, InlineArgument) {
  const TextureSpec s = parse_spec_argument("sample:size=0.5,count=3,tint=(0.1, 0.2,0.3),mode=rough,flip=false,seed=9");
  EXPECT_EQ(s.shader, "sample");
  EXPECT_EQ(s.seed, 9u);
  const auto packed = resolve(sample_decl(), s);
  EXPECT_EQ(packed, (std::vector<float>{0.5f, 3, 0.1f, 0.2f, 0.3f, 2, 0}));
}

TEST(Spec, InlineArgumentLongerThanAFileNameIsParsed) {
  // A match result's every parameter written inline is easily over 255 bytes, the longest file
  // name: checking whether it names a file must not fail ("File name too long").
  std::string arg = "sample:size=0.5,count=3,tint=(0.100000001, 0.200000003, 0.300000012),mode=rough";
  while (arg.size() < 400) arg += ",flip=false";
  const TextureSpec s = parse_spec_argument(arg);
  EXPECT_EQ(s.shader, "sample");
  EXPECT_EQ(resolve(sample_decl(), s), (std::vector<float>{0.5f, 3, 0.1f, 0.2f, 0.3f, 2, 0}));
}

TEST(Spec, BareNameUsesDefaults) {
  const TextureSpec s = parse_spec_argument("sample");
  EXPECT_TRUE(s.params.empty());
  EXPECT_EQ(resolve(sample_decl(), s), sample_decl().default_packed());
}

TEST(Spec, HexColourIsSrgb) {
  const auto packed = resolve(sample_decl(), parse_spec_argument("sample:tint=#ff8000"));
  EXPECT_FLOAT_EQ(packed[2], 1.0f);
  EXPECT_NEAR(packed[3], 0.2158605f, 1e-4f);  // sRGB 128/255 -> linear
  EXPECT_FLOAT_EQ(packed[4], 0.0f);
}

TEST(Spec, JsonFileRoundTrip) {
  testing::TempDir dir;
  const ShaderDecl d = sample_decl();
  const TextureSpec full = spec_from_packed(d, {0.3f, 7, 0.1f, 0.2f, 0.3f, 0, 1}, 42);
  const auto path = dir / "spec.json";
  std::ofstream(path) << full.to_json().dump(2);
  const TextureSpec back = parse_spec_argument(path.string());
  EXPECT_EQ(back.shader, "sample");
  EXPECT_EQ(back.seed, 42u);
  EXPECT_EQ(back.params.at("mode"), "flat");
  EXPECT_EQ(back.params.at("flip"), true);
  EXPECT_EQ(back.params.at("count"), 7);
  EXPECT_EQ(resolve(d, back), (std::vector<float>{0.3f, 7, 0.1f, 0.2f, 0.3f, 0, 1}));
}

TEST(Spec, RejectsUnknownParameterNamingTheKnownOnes) {
  try {
    resolve(sample_decl(), parse_spec_argument("sample:sise=0.5"));
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_NE(e.message().find("sise"), std::string::npos);
    EXPECT_NE(e.hint().find("size"), std::string::npos);
  }
}

TEST(Spec, RejectsOutOfRangeWrongTypeAndNonInteger) {
  const ShaderDecl d = sample_decl();
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:size=2")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:size=0.001")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:count=2.5")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:count=13")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:tint=(1,2,0)")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:tint=(1,0)")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:mode=spiky")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:flip=3")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("sample:size=abc")), UsageError);
}

// The bounds a shader declares are accepted as the user types them: 0.05 and 0.95 are not exactly
// representable, and as doubles they lie outside the float bounds (they were rejected: "value
// 0.05 is out of range ... [0.05, 0.95]").
TEST(Spec, DeclaredBoundsAreInRange) {
  const ShaderDecl d = parse_shader("shaders/test/duty.cl", R"(// @shader "x"
// @param float duty = 0.5 [0.05, 0.95] "Fraction"
float3 shade(float2 p, float fw, uint seed, const Params P) { return (float3)(P.duty); }
)");
  EXPECT_NO_THROW(resolve(d, parse_spec_argument("duty:duty=0.05")));
  EXPECT_NO_THROW(resolve(d, parse_spec_argument("duty:duty=0.95")));
  EXPECT_THROW(resolve(d, parse_spec_argument("duty:duty=0.0499")), UsageError);
  EXPECT_THROW(resolve(d, parse_spec_argument("duty:duty=0.9501")), UsageError);
}

TEST(Spec, MalformedArgumentsAreUsageErrors) {
  EXPECT_THROW(parse_spec_argument(":a=1"), UsageError);
  EXPECT_THROW(parse_spec_argument("sample:size"), UsageError);
  EXPECT_THROW(parse_spec_argument("sample:seed=-1"), UsageError);
  EXPECT_THROW(TextureSpec::from_json(nlohmann::json::parse(R"({"params": {}})")), UsageError);
  EXPECT_THROW(TextureSpec::from_json(nlohmann::json::parse(R"({"shader": "x", "seed": 1.5})")), UsageError);
}

TEST(Spec, BadJsonFileIsAUsageError) {
  testing::TempDir dir;
  std::ofstream(dir / "bad.json") << "{\"shader\": ";
  EXPECT_THROW(parse_spec_argument((dir / "bad.json").string()), UsageError);
}

}  // namespace
}  // namespace proctex
