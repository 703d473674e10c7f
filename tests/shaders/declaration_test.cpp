// The shader file format: declarations parse into typed parameters; malformed ones name file:line.
#include <gtest/gtest.h>

#include "core/error.h"
#include "shaders/codegen.h"
#include "shaders/library.h"
#include "shaders/shader.h"

namespace proctex {
namespace {

const char* kGood = R"(// @shader "A test shader"
// @param float size = 0.25 [0.01, 1] log "Feature size"
// @param int   count = 4 [1, 12] "How many"
// @param color tint = (0.5, 0.25, 1) "Tint"
// @param enum  mode = wavy {flat, wavy, rough} "Mode"
// @param bool  flip = true fixed "Mirror it"
float3 shade(float2 p, float fw, uint seed, const Params P) { return P.tint; }
)";

TEST(Declaration, ParsesEveryType) {
  const ShaderDecl d = parse_shader("shaders/test/sample.cl", kGood);
  EXPECT_EQ(d.name, "sample");
  EXPECT_EQ(d.family, "test");
  EXPECT_EQ(d.help, "A test shader");
  ASSERT_EQ(d.params.size(), 5u);
  EXPECT_EQ(d.packed_size, 7);  // the colour packs three floats

  const auto& size = d.params[0];
  EXPECT_EQ(size.type, ParamType::Float);
  EXPECT_EQ(size.scale, Scale::Log);
  EXPECT_FLOAT_EQ(size.min, 0.01f);
  EXPECT_FLOAT_EQ(size.max, 1.0f);
  EXPECT_FLOAT_EQ(size.default_value[0], 0.25f);
  EXPECT_TRUE(size.searchable);

  EXPECT_EQ(d.params[1].type, ParamType::Int);
  EXPECT_TRUE(d.params[1].discrete());
  EXPECT_EQ(d.params[2].type, ParamType::Color);
  EXPECT_EQ(d.params[2].offset, 2);
  EXPECT_EQ(d.params[2].default_value, (std::vector<float>{0.5f, 0.25f, 1.0f}));
  EXPECT_EQ(d.params[3].enum_values, (std::vector<std::string>{"flat", "wavy", "rough"}));
  EXPECT_FLOAT_EQ(d.params[3].default_value[0], 1.0f);
  EXPECT_FALSE(d.params[4].searchable);
  EXPECT_EQ(d.default_packed(), (std::vector<float>{0.25f, 4, 0.5f, 0.25f, 1, 1, 1}));
}

TEST(Declaration, SourceHashChangesWithSource) {
  const auto a = parse_shader("shaders/test/sample.cl", kGood);
  const auto b = parse_shader("shaders/test/sample.cl", std::string(kGood) + "\n");
  EXPECT_EQ(a.source_hash, parse_shader("shaders/test/sample.cl", kGood).source_hash);
  EXPECT_NE(a.source_hash, b.source_hash);
}

TEST(Declaration, GeneratedCodeDeclaresStructEnumsAndKernel) {
  const std::string program = generate_program(parse_shader("shaders/test/sample.cl", kGood));
  EXPECT_NE(program.find("float3 tint;"), std::string::npos);
  EXPECT_NE(program.find("#define MODE_ROUGH 2"), std::string::npos);
  EXPECT_NE(program.find("#line 1 \"shaders/test/sample.cl\""), std::string::npos);
  EXPECT_NE(program.find("__kernel void pt_render"), std::string::npos);
}

struct BadCase {
  const char* line;
  int line_number;
  const char* expect;
};

class MalformedDeclaration : public ::testing::TestWithParam<BadCase> {};

TEST_P(MalformedDeclaration, NamesFileAndLine) {
  const BadCase c = GetParam();
  const std::string source = std::string("// @shader \"x\"\n// @param float ok = 0.5 [0, 1] \"fine\"\n") + c.line +
                             "\nfloat3 shade(float2 p, float fw, uint seed, const Params P) { return 0; }\n";
  try {
    parse_shader("shaders/test/bad.cl", source);
    FAIL() << "accepted: " << c.line;
  } catch (const Error& e) {
    const std::string where = "shaders/test/bad.cl:" + std::to_string(c.line_number);
    EXPECT_NE(e.message().find(where), std::string::npos) << e.message();
    EXPECT_NE(e.message().find(c.expect), std::string::npos) << e.message();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, MalformedDeclaration,
    ::testing::Values(BadCase{"// @param quux a = 1 [0, 2] \"h\"", 3, "unknown parameter type"},
                      BadCase{"// @param float a = 3 [0, 2] \"h\"", 3, "outside its range"},
                      BadCase{"// @param float a = 1 [2, 0] \"h\"", 3, "min < max"},
                      BadCase{"// @param float a = 1 [0, 2] log \"h\"", 3, "positive minimum"},
                      BadCase{"// @param int a = 1.5 [0, 2] \"h\"", 3, "integer"},
                      BadCase{"// @param float a = 1 [0, 2]", 3, "help"},
                      BadCase{"// @param float a = 1 [0, 2] sideways \"h\"", 3, "unknown flag"},
                      BadCase{"// @param float ok = 1 [0, 2] \"h\"", 3, "declared twice"},
                      BadCase{"// @param float seed = 1 [0, 2] \"h\"", 3, "reserved"},
                      BadCase{"// @param color c = (1, 0) \"h\"", 3, "three components"},
                      BadCase{"// @param enum e = z {a, b} \"h\"", 3, "not one of its values"},
                      BadCase{"// @param enum e = a {a} \"h\"", 3, "at least two"},
                      BadCase{"// @param bool b = maybe \"h\"", 3, "true or false"},
                      BadCase{"// @param float a = abc [0, 2] \"h\"", 3, "as a number"},
                      BadCase{"// @parma float a = 1 [0, 2] \"h\"", 3, "unknown declaration"},
                      BadCase{"// @param float a = 1 [0, 2] period=0 \"h\"", 3, "must be positive"},
                      BadCase{"// @param float a = 1 [1, 2] log period=1 \"h\"", 3, "linear float"},
                      BadCase{"// @param int a = 1 [0, 2] period=1 \"h\"", 3, "linear float"},
                      BadCase{"// @param float a = 1 [0, 2] period=360/ok \"h\"", 3, "not an int parameter"},
                      BadCase{"// @param float a = 1 [0, 2] period=360/nothing \"h\"", 3, "not an int parameter"},
                      BadCase{"// @param float a = 1 [0, 2] period=x/y \"h\"", 3, "as a number"},
                      BadCase{"// @param float a = 1 [0, 2] exchange=ok \"h\"", 3, "two parameter names"},
                      BadCase{"// @param float a = 1 [0, 2] exchange=ok/nothing \"h\"", 3, "two other float parameters"},
                      BadCase{"// @param float a = 1 [0, 2] exchange=ok/a \"h\"", 3, "two other float parameters"},
                      BadCase{"// @param float a = 1 [0, 2] exchange=ok/ok \"h\"", 3, "two other float parameters"},
                      BadCase{"// @param int a = 1 [0, 2] exchange=ok/ok \"h\"", 3, "linear float"},
                      BadCase{"// @param float a = 1 [0, 2] needs=1x \"h\"", 3, "expected a parameter name"},
                      BadCase{"// @param float a = 1 [0, 2] needs=nothing \"h\"", 3, "another linear float"},
                      BadCase{"// @param float a = 1 [0, 2] needs=a \"h\"", 3, "another linear float"},
                      BadCase{"// @param bool a = false needs=ok \"h\"", 3, "only a float or int"}));

// A symmetry period is data (issue 12: a star turned by 360/n is the same star): constant or
// divided by a count, read back per point; values are reduced into [min, min + period) and
// compared modulo the period.
TEST(Declaration, PeriodIsReadAndUsedModuloTheCount) {
  const char* source = R"(// @shader "A test shape"
// @param int   n   = 5 [1, 12] "Points"
// @param float rot = 0 [0, 180] period=360/n "Rotation"
// @param float dir = 0 [0, 180] period=180 "Direction"
// @param float other = 0 [0, 180] "Not periodic"
float3 shade(float2 p, float fw, uint seed, const Params P) { return 0; }
)";
  const ShaderDecl d = parse_shader("shaders/test/periodic.cl", source);
  const ParamDecl& rot = d.params[1];
  EXPECT_FLOAT_EQ(rot.period, 360.0f);
  EXPECT_EQ(rot.period_per, "n");
  EXPECT_EQ(d.params[2].period_per, "");
  EXPECT_EQ(rot.help, "Rotation");
  std::vector<float> packed = {8, 50, 180, 170};  // n = 8: the period is 45 degrees
  EXPECT_DOUBLE_EQ(symmetry_period(d, rot, packed), 45.0);
  EXPECT_DOUBLE_EQ(symmetry_period(d, d.params[2], packed), 180.0);
  EXPECT_DOUBLE_EQ(symmetry_period(d, d.params[3], packed), 0.0);
  const auto canonical = canonical_packed(d, packed);
  EXPECT_FLOAT_EQ(canonical[0], 8.0f);
  EXPECT_NEAR(canonical[1], 5.0f, 1e-4);   // 50 - 45
  EXPECT_NEAR(canonical[2], 0.0f, 1e-4);   // 180 is 0 again
  EXPECT_FLOAT_EQ(canonical[3], 170.0f);  // no period: left alone
  // 1 and 44 degrees are 2 degrees apart as 8-pointed stars, 43 apart as anything else.
  EXPECT_NEAR(parameter_difference(d, rot, 1.0f, 44.0f, packed), 2.0, 1e-5);
  EXPECT_NEAR(parameter_difference(d, rot, 1.0f, 134.0f, packed), 2.0, 1e-5);
  EXPECT_NEAR(parameter_difference(d, rot, 10.0f, 30.0f, packed), 20.0, 1e-5);
  EXPECT_NEAR(parameter_difference(d, d.params[3], 1.0f, 179.0f, packed), 178.0, 1e-5);
  packed[0] = 5;  // 72 degrees: 1 and 44 are 29 apart (44 - 72 = -28), 10 and 30 still 20
  EXPECT_NEAR(parameter_difference(d, rot, 1.0f, 44.0f, packed), 29.0, 1e-5);
  EXPECT_NEAR(parameter_difference(d, rot, 10.0f, 30.0f, packed), 20.0, 1e-5);
  EXPECT_NEAR(canonical_packed(d, packed)[1], 50.0f, 1e-5);
}

// An exchange symmetry (issue 12: a rectangle at 0 degrees is the one at 90 with its width and
// height exchanged) names two float parameters of one range; the library's two shapes declare it.
TEST(Declaration, ExchangeNamesTwoFloatsOfOneRange) {
  const std::string head = "// @shader \"x\"\n// @param float w = 0.5 [0, 1] \"w\"\n";
  const std::string shade = "float3 shade(float2 p, float fw, uint seed, const Params P) { return 0; }\n";
  const ShaderDecl d = parse_shader("shaders/test/ex.cl", head + "// @param float h = 0.5 [0, 1] \"h\"\n"
                                    "// @param float rot = 0 [0, 90] exchange=w/h \"r\"\n" + shade);
  EXPECT_EQ(d.find("rot")->exchange, (std::vector<std::string>{"w", "h"}));
  EXPECT_TRUE(d.find("w")->exchange.empty());
  try {
    parse_shader("shaders/test/ex.cl", head + "// @param float h = 0.5 [0, 2] \"h\"\n"
                                       "// @param float rot = 0 [0, 90] exchange=w/h \"r\"\n" + shade);
    FAIL() << "accepted an exchange of two ranges";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("shaders/test/ex.cl:4"), std::string::npos) << e.message();
    EXPECT_NE(e.message().find("same range"), std::string::npos) << e.message();
  }
  for (const char* shape : {"rectangle", "superellipse"})
    EXPECT_EQ(ShaderLibrary::builtin().get(shape).find("rotation")->exchange,
              (std::vector<std::string>{"width", "height"})) << shape;
}

// A dependency (issue 12: a stripe's wave frequency does nothing while the wave is off) names
// another linear float; the stripes declare it, and a log-scaled gate (whose minimum is not "off")
// is refused.
TEST(Declaration, NeedsNamesTheFloatThatSwitchesAParameterOn) {
  const std::string head = "// @shader \"x\"\n// @param float amp = 0 [0, 1] \"a\"\n";
  const std::string shade = "float3 shade(float2 p, float fw, uint seed, const Params P) { return 0; }\n";
  const ShaderDecl d = parse_shader("shaders/test/nd.cl", head + "// @param float f = 3 [1, 12] needs=amp \"f\"\n" + shade);
  EXPECT_EQ(d.find("f")->needs, "amp");
  EXPECT_TRUE(d.find("amp")->needs.empty());
  try {
    parse_shader("shaders/test/nd.cl", "// @shader \"x\"\n// @param float amp = 1 [0.1, 1] log \"a\"\n"
                                       "// @param float f = 3 [1, 12] needs=amp \"f\"\n" + shade);
    FAIL() << "accepted a log-scaled gate";
  } catch (const Error& e) {
    EXPECT_NE(e.message().find("shaders/test/nd.cl:3"), std::string::npos) << e.message();
    EXPECT_NE(e.message().find("linear float"), std::string::npos) << e.message();
  }
  EXPECT_EQ(ShaderLibrary::builtin().get("stripes").find("wave_frequency")->needs, "wave");
  EXPECT_EQ(ShaderLibrary::builtin().get("grid").find("subdivisions")->needs, "minor_strength");
}

// An answer whose gate is off reports what it does not use at its default, as a period reports its
// canonical value: a grid found with 8 subdivisions at minor strength 0 (session 21's benchmark
// target 4, whose own subdivisions are 1) is the grid without minor lines, subdivisions 1.
TEST(Declaration, AParameterWhoseGateIsOffReadsAsItsDefault) {
  const ShaderDecl& grid = ShaderLibrary::builtin().get("grid");
  auto packed = grid.default_packed();
  const auto at = [&](const char* name) -> float& { return packed[grid.find(name)->offset]; };
  at("subdivisions") = 8;
  at("minor_width") = 0.839f;
  at("minor_strength") = 0.0f;
  auto canonical = canonical_packed(grid, packed);
  EXPECT_EQ(canonical[grid.find("subdivisions")->offset], 1.0f);
  EXPECT_EQ(canonical[grid.find("minor_width")->offset], grid.find("minor_width")->default_value[0]);
  at("minor_strength") = 0.01f;  // on, however faint: kept
  canonical = canonical_packed(grid, packed);
  EXPECT_EQ(canonical[grid.find("subdivisions")->offset], 8.0f);
  EXPECT_EQ(canonical[grid.find("minor_width")->offset], 0.839f);
}

TEST(Declaration, MissingShaderLineIsAnError) {
  EXPECT_THROW(parse_shader("shaders/t/a.cl", "float3 shade(float2 p, float fw, uint seed, const Params P) {}"),
               Error);
}

TEST(Declaration, MissingShadeFunctionIsAnError) {
  EXPECT_THROW(parse_shader("shaders/t/a.cl", "// @shader \"x\"\nfloat3 other() {}"), Error);
}

}  // namespace
}  // namespace proctex
