// Rotations on the sphere, stamps, pens and edit sessions.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "rgbn/edit.h"
#include "support.h"

using namespace proctex::rgbn;
using namespace rgbn_test;
using nlohmann::json;

namespace {
Vec3 unit(float x, float y, float z) {
  const float l = std::sqrt(x * x + y * y + z * z);
  return {x / l, y / l, z / l};
}
double angle(const Vec3& a, const Vec3& b) { return angle_deg(a.data(), b.data()); }
}  // namespace

TEST(RgbnRotation, OrthonormalDetPlusOneConstantSpeedPast90Degrees) {
  std::mt19937 rng(11);
  std::normal_distribution<float> g(0, 1);
  for (int k = 0; k < 200; ++k) {
    const Vec3 a = unit(g(rng), g(rng), g(rng)), b = unit(g(rng), g(rng), g(rng));
    const double t = std::uniform_real_distribution<double>(0, 1)(rng);
    const Mat3 r = arc_rotation(a, b, t);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        double d = 0;
        for (int c = 0; c < 3; ++c) d += r[c][i] * r[c][j];
        EXPECT_NEAR(d, i == j ? 1.0 : 0.0, 1e-6);  // float axis
      }
    const double det = r[0][0] * (r[1][1] * r[2][2] - r[1][2] * r[2][1]) - r[0][1] * (r[1][0] * r[2][2] - r[1][2] * r[2][0]) +
                       r[0][2] * (r[1][0] * r[2][1] - r[1][1] * r[2][0]);
    EXPECT_NEAR(det, 1.0, 1e-6);
    // Constant speed: the angle travelled is t times the arc, also past 90 degrees.
    const double theta = angle(a, b);
    EXPECT_NEAR(angle(a, apply(r, a)), t * theta, 1e-3);
    EXPECT_NEAR(angle(apply(r, a), b), (1 - t) * theta, 1e-3);
    EXPECT_LT(angle(slerp(a, b, t), apply(r, a)), 1e-3);
  }
  // Endpoints exact; antipodal vectors still rotate.
  const Vec3 a = unit(0.2f, 0.1f, 0.9f), b = unit(-0.7f, 0.3f, -0.2f);
  EXPECT_LT(angle(slerp(a, b, 0), a), 1e-4);
  EXPECT_LT(angle(slerp(a, b, 1), b), 1e-3);
  const Vec3 z = {0, 0, 1}, mz = {0, 0, -1};
  EXPECT_NEAR(angle(slerp(z, mz, 0.5), z), 90.0, 1e-3);
}

TEST(RgbnRotation, SaturationStopsOnTheArcAtSinXi) {
  const Vec3 a = unit(0.1f, 0.2f, 0.95f), b = unit(0.9f, -0.3f, -0.1f);
  const double xi = 20;
  const Vec3 k = saturate_on_arc(a, b, xi);
  EXPECT_NEAR(k[2], std::sin(xi * M_PI / 180), 1e-5);
  // On the arc: coplanar with a and b, and between them.
  const double det = a[0] * (b[1] * k[2] - b[2] * k[1]) - a[1] * (b[0] * k[2] - b[2] * k[0]) + a[2] * (b[0] * k[1] - b[1] * k[0]);
  EXPECT_NEAR(det, 0, 1e-5);
  EXPECT_NEAR(angle(a, k) + angle(k, b), angle(a, b), 1e-3);
  // Admissible targets are untouched.
  const Vec3 c = unit(0.3f, 0.3f, 0.9f);
  EXPECT_LT(angle(saturate_on_arc(a, c, xi), c), 1e-6);
}

TEST(RgbnStamp, FlatStampReproducesTheBaseAndLeavesTheRestAlone) {
  const Rgbn base = from_height(periodic_field(96, 80, 12, 8.0f), 1.0f, false);
  // A flat stamp ((0,0,1) everywhere) changes nothing.
  Rgbn flat = base;
  const EditReport r0 = apply_edit(flat, json{{"op", "stamp"}, {"at", {40, 30}}, {"shape", "dome"}, {"radius", 12}, {"height", 0}});
  EXPECT_GT(r0.pixels_changed, 300u);
  EXPECT_LT(max_angle(flat, base), 1e-3);
  // A real stamp changes pixels only inside its footprint.
  Rgbn out = base;
  const EditReport r = apply_edit(out, json{{"op", "stamp"}, {"at", {40, 30}}, {"shape", "ring"}, {"radius", 12}, {"height", 5}, {"angle", 30}});
  size_t changed = 0;
  for (int y = 0; y < base.height; ++y)
    for (int x = 0; x < base.width; ++x) {
      const bool same = std::equal(base.n(x, y), base.n(x, y) + 3, out.n(x, y));
      if (std::hypot(x - 40.0, y - 30.0) > 12 * std::sqrt(2.0) + 3) {
        EXPECT_TRUE(same) << x << "," << y;
      }
      changed += !same;
    }
  EXPECT_GT(changed, 200u);
  EXPECT_LT(max_norm_error(out), 1e-5);
  EXPECT_GE(r.integrability_before, 0.0);
}

TEST(RgbnStamp, SameStampLooksDifferentOnDifferentBaseNormals) {
  // On a flat base the stamp's normals appear as they are; on a tilted base they are tilted with it.
  Rgbn flat(64, 64), tilted(64, 64);
  const float s = std::sin(0.5f), c = std::cos(0.5f);
  for (size_t i = 0; i < tilted.size(); ++i) tilted.normal[3 * i] = s, tilted.normal[3 * i + 2] = c;
  const json op = {{"op", "stamp"}, {"at", {32, 32}}, {"shape", "dome"}, {"radius", 10}, {"height", 4}};
  apply_edit(flat, op);
  apply_edit(tilted, op);
  const Rgbn stamp = stamp_shape("dome", 10, 4);
  const int sc = stamp.width / 2;
  // Pixel 5 to the right of the centre: flat gets the stamp normal, tilted gets it rotated by 0.5 rad about y.
  const float* sn = stamp.n(sc + 5, sc);
  EXPECT_LT(angle_deg(flat.n(37, 32), sn), 0.5);
  const Vec3 rotated = {sn[0] * c + sn[2] * s, sn[1], -sn[0] * s + sn[2] * c};
  EXPECT_LT(angle_deg(tilted.n(37, 32), rotated.data()), 0.5);
}

TEST(RgbnStamp, OnSmoothedBaseNormalsAStampReplacesTheDetailUnderIt) {
  // A gentle tilt plus fine noise (the "detail" a user wants a stamp to replace).
  const int w = 96, h = 80;
  HeightField z{w, h, std::vector<float>(size_t(w) * h)};
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) z.at(x, y) = 0.3f * x + 0.6f * u(rng);
  const Rgbn base = from_height(z, 1.0f, false);
  auto roughness = [](const Rgbn& im, int cx, int cy, int r) {  // mean angle between horizontal neighbours
    double sum = 0;
    int n = 0;
    for (int y = cy - r; y <= cy + r; ++y)
      for (int x = cx - r; x < cx + r; ++x) sum += angle_deg(im.n(x, y), im.n(x + 1, y)), ++n;
    return sum / n;
  };
  // A flat stamp on the current normals changes nothing; on the smoothed base it removes the noise
  // and keeps the tilt.
  Rgbn out = base;
  apply_edit(out, json{{"op", "stamp"}, {"at", {48, 40}}, {"shape", "dome"}, {"radius", 12}, {"height", 0}, {"base_sigma", 3}});
  EXPECT_LT(roughness(out, 48, 40, 6), 0.3 * roughness(base, 48, 40, 6));
  const float* n = out.n(48, 40);
  const float tilt[3] = {-0.3f / std::sqrt(1.09f), 0.0f, 1.0f / std::sqrt(1.09f)};
  EXPECT_LT(angle_deg(n, tilt), 4.0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (std::hypot(x - 48.0, y - 40.0) > 12 * std::sqrt(2.0) + 3) {
        ASSERT_TRUE(std::equal(base.n(x, y), base.n(x, y) + 3, out.n(x, y))) << x << "," << y;
      }
  EXPECT_LT(max_norm_error(out), 1e-5);
  // A pen on the smoothed base: along the groove the noise is gone; on the current normals it
  // shows through.
  Rgbn pen = base, pen_raw = base;
  const json p = {{"op", "pen"}, {"points", {{10, 40}, {86, 40}}}, {"width", 6}, {"depth", 2}, {"profile", "groove"}};
  json pb = p;
  pb["base_sigma"] = 3;
  apply_edit(pen, pb);
  apply_edit(pen_raw, p);
  // Along the groove's wall (3 px below the line) the relief is the profile on a smooth base.
  auto wall = [](const Rgbn& im) {
    double sum = 0;
    for (int x = 20; x < 76; ++x) sum += angle_deg(im.n(x, 43), im.n(x + 1, 43));
    return sum / 56;
  };
  EXPECT_LT(wall(pen), 0.3 * wall(pen_raw));
  EXPECT_THROW(apply_edit(out, json{{"op", "stamp"}, {"at", {48, 40}}, {"base_sigma", -1}}), proctex::UsageError);
}

TEST(RgbnPen, GrooveOnFlatBaseFollowsTheProfileAndStaysInside) {
  Rgbn im(80, 60);
  const double width = 6, depth = 2;
  const EditReport r = apply_edit(im, json{{"op", "pen"}, {"points", {{10, 30}, {70, 30}}}, {"width", width}, {"depth", depth}, {"profile", "groove"}});
  EXPECT_GT(r.pixels_changed, 500u);
  // Below the line (s = 3 px, direction (0,-1) in y-up): normal ~ (-h'(s) * dir, 1) normalised.
  const double u = 3 / width, dh = 4 * depth * u * (1 - u * u) / width;
  const float* n = im.n(40, 33);
  const double l = std::sqrt(dh * dh + 1);
  EXPECT_NEAR(n[0], 0, 1e-5);
  EXPECT_NEAR(n[1], dh / l, 1e-4);  // a groove's far wall faces the line: +y for pixels below it
  EXPECT_NEAR(n[2], 1 / l, 1e-4);
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 80; ++x)
      if (std::abs(y - 30) >= width || x < 10 - width || x > 70 + width) {
        EXPECT_EQ(im.n(x, y)[2], 1.0f) << x << "," << y;
      }
  // A vee has a crease on the medial axis: opposite tilts on either side.
  Rgbn v(80, 60);
  apply_edit(v, json{{"op", "pen"}, {"points", {{10, 30}, {70, 30}}}, {"width", width}, {"depth", depth}, {"profile", "vee"}});
  EXPECT_GT(v.n(40, 31)[1], 0.1f);
  EXPECT_LT(v.n(40, 29)[1], -0.1f);
}

TEST(RgbnEdit, SaturationBoundHoldsAfterEveryEditAndSessionsReplay) {
  const Rgbn base = from_height(periodic_field(96, 96, 13, 20.0f), 1.0f, false);
  const double xi = 30;
  const json session = json::array({
      {{"op", "rotate"}, {"target", {1, 0, 0.05}}, {"amount", 0.9}, {"mode", "blend"}, {"region", {{"disc", {40, 40, 30}}}}, {"xi", xi}},
      {{"op", "stamp"}, {"at", {60, 50}}, {"shape", "dimple"}, {"radius", 14}, {"height", 30}, {"xi", xi}},
      {{"op", "stamp"}, {"at", {30, 60}}, {"shape", "dome"}, {"radius", 10}, {"height", 25}, {"base_sigma", 3}, {"xi", xi}},
      {{"op", "pen"}, {"points", {{5, 80}, {90, 70}}}, {"width", 5}, {"depth", 8}, {"profile", "vee"}, {"xi", xi}},
      {{"op", "filter"}, {"filter", "sharpen"}, {"amount", 4}, {"region", {{"rect", {10, 10, 40, 30}}}}, {"xi", xi}},
      {{"op", "saturate"}, {"xi", xi}},
      {{"op", "paint"}, {"color", {0.8, 0.1, 0.1}}, {"region", {{"disc", {20, 20, 5}}}}},
  });
  std::vector<EditReport> reps;
  const Rgbn out = apply_edits(base, session, &reps);
  ASSERT_EQ(reps.size(), 7u);
  const float s = float(std::sin(xi * M_PI / 180));
  for (size_t i = 0; i < out.size(); ++i) EXPECT_GE(out.normal[3 * i + 2], s - 1e-5f);
  EXPECT_LT(max_norm_error(out), 1e-5);
  for (const auto& r : reps) {
    if (r.op != "saturate") {
        EXPECT_GT(r.pixels_changed, 0u) << r.op;
      }
  }
  // A saturated stamp makes the height field's normals measurably less integrable.
  Rgbn stamped = base;
  const EditReport sr = apply_edit(stamped, session[1]);
  EXPECT_LT(sr.integrability_before, 1e-3);
  EXPECT_GT(sr.integrability_after, 10 * sr.integrability_before);
  // Replay is deterministic; undo = replay fewer ops.
  const Rgbn again = apply_edits(base, session);
  EXPECT_EQ(again.normal, out.normal);
  EXPECT_EQ(again.albedo, out.albedo);
  const Rgbn two = apply_edits(base, session, nullptr, {}, 2);
  Rgbn step = base;
  apply_edit(step, session[0]);
  apply_edit(step, session[1]);
  EXPECT_EQ(two.normal, step.normal);
  // The rotation's footprint: pixels outside the disc are untouched.
  Rgbn rot = base;
  apply_edit(rot, session[0]);
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x)
      if (std::hypot(x - 40.0, y - 40.0) > 30.5) {
        EXPECT_TRUE(std::equal(base.n(x, y), base.n(x, y) + 3, rot.n(x, y)));
      }
}

TEST(RgbnEdit, MalformedOperationsAreUsageErrors) {
  Rgbn im(16, 16);
  EXPECT_THROW(apply_edit(im, json{{"op", "explode"}}), proctex::UsageError);
  EXPECT_THROW(apply_edit(im, json{{"nop", 1}}), proctex::UsageError);
  EXPECT_THROW(apply_edit(im, json{{"op", "stamp"}}), proctex::UsageError);
  EXPECT_THROW(apply_edit(im, json{{"op", "pen"}, {"points", {{1, 2}}}, {"width", "wide"}}), proctex::UsageError);
  EXPECT_THROW(apply_edit(im, json{{"op", "rotate"}, {"region", {{"blob", 1}}}}), proctex::UsageError);
  EXPECT_THROW(apply_edits(im, json{{"ops", 3}}), proctex::UsageError);
  // The image is unchanged by failed ops.
  EXPECT_EQ(im.normal, Rgbn(16, 16).normal);
}
