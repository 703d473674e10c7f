// The JSON API of proctex serve against a real server on loopback: shaders, render, compare,
// catalogue info, the OpenAPI description, the web pages, and the bearer token.
#include <gtest/gtest.h>

#include "core/error.h"
#include "image/image.h"
#include "tests/server/support.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using namespace proctex::testing;
using nlohmann::json;

class Api : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    catalog_ = new fs::path(test_catalog());
  }
  static void TearDownTestSuite() { delete catalog_; }
  server::ServerOptions options() {
    server::ServerOptions o;
    o.port = 0;
    o.catalog = *catalog_;
    o.data = dir_ / "data";
    return o;
  }
  // Decodes image bytes through image/ (a temp file) to check what a client would get.
  Image decode(const std::string& bytes, const std::string& ext) {
    const fs::path p = dir_ / ("decoded" + ext);
    std::ofstream(p, std::ios::binary) << bytes;
    return load_image(p);
  }
  static fs::path* catalog_;
  TempDir dir_;
};
fs::path* Api::catalog_ = nullptr;

TEST_F(Api, ListsShadersWithTheirParameters) {
  RunningServer srv(options());
  auto c = srv.client();
  auto r = c.Get("/api/shaders");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  const json list = body_json(r);
  ASSERT_TRUE(list.is_array());
  EXPECT_GE(list.size(), 50u);  // the whole built-in library
  const auto bricks = std::find_if(list.begin(), list.end(), [](const json& s) { return s["name"] == "bricks"; });
  ASSERT_NE(bricks, list.end());
  bool rows = false;
  for (const auto& p : (*bricks)["params"])
    if (p["name"] == "rows") {
      rows = true;
      EXPECT_EQ(p["type"], "int");
      EXPECT_EQ(p["range"].size(), 2u);
    }
  EXPECT_TRUE(rows);
  r = c.Get("/api/shaders/nosuchshader");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
  EXPECT_TRUE(body_json(r).contains("error"));
}

TEST_F(Api, RendersPngAndExrOfTheRequestedSize) {
  RunningServer srv(options());
  auto c = srv.client();
  auto r = c.Post("/api/render", R"({"spec": {"shader": "bricks", "params": {"rows": 6}, "seed": 3}, "width": 96, "height": 64})",
                  "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "image/png");
  const Image png = decode(r->body, ".png");
  EXPECT_EQ(png.width, 96);
  EXPECT_EQ(png.height, 64);
  // The same spec renders the same pixels as the library does (deterministic from the seed).
  auto again = c.Post("/api/render", R"({"spec": {"shader": "bricks", "params": {"rows": 6}, "seed": 3}, "width": 96, "height": 64})",
                      "application/json");
  EXPECT_EQ(again->body, r->body);
  // Another seed is another wall.
  auto other = c.Post("/api/render", R"({"spec": {"shader": "bricks", "params": {"rows": 6}, "seed": 4}, "width": 96, "height": 64})",
                      "application/json");
  EXPECT_NE(other->body, r->body);

  r = c.Post("/api/render", R"({"spec": "stripes:duty=0.3", "size": 32, "format": "exr"})", "application/json");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body.substr(0, 4), std::string("\x76\x2f\x31\x01", 4));
  const Image exr = decode(r->body, ".exr");
  EXPECT_EQ(exr.width, 32);
}

TEST_F(Api, RejectsBadRenderRequestsWithJsonErrors) {
  RunningServer srv(options());
  auto c = srv.client();
  struct Case {
    std::string body;
    std::string mentions;
  };
  const std::vector<Case> cases = {
      {R"({"spec": {"shader": "brickz"}})", "bricks"},                     // unknown shader, with a suggestion
      {R"({"spec": {"shader": "bricks", "params": {"rows": 1000}}})", "rows"},  // out of range
      {R"({"spec": {"shader": "bricks", "params": {"nope": 1}}})", "nope"},   // unknown parameter
      {R"({"spec": {"shader": "bricks"}, "size": 100000})", "size"},          // absurd size
      {R"({"spec": {"shader": "bricks"}, "size": -5})", "size"},
      {R"({"spec": {"shader": "bricks"}, "size": "big"})", "size"},
      {R"({"spec": {"shader": "bricks"}, "format": "bmp"})", "format"},
      {R"({"size": 64})", "spec"},
      {R"({"spec": {"shader": "bricks"})", "JSON"},  // malformed JSON
      {R"([1, 2])", "object"},
  };
  for (const auto& k : cases) {
    auto r = c.Post("/api/render", k.body, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << k.body;
    const json j = body_json(r);
    ASSERT_TRUE(j.is_object()) << r->body;
    EXPECT_NE((j.value("error", "") + " " + j.value("hint", "")).find(k.mentions), std::string::npos) << k.body << " -> " << r->body;
  }
  auto r = c.Get("/api/no/such/endpoint");
  EXPECT_EQ(r->status, 404);
  EXPECT_TRUE(body_json(r).contains("error"));
  EXPECT_EQ(c.Get("/api/health")->status, 200);  // still serving
}

TEST_F(Api, ComparesTwoUploadedImages) {
  RunningServer srv(options());
  auto c = srv.client();
  const std::string brick = slurp(brick_photo());
  const std::string stripes = c.Post("/api/render", R"({"spec": "stripes", "size": 256})", "application/json")->body;
  httplib::MultipartFormDataItems same = {{"a", brick, "a.png", "image/png"}, {"b", brick, "b.png", "image/png"}};
  auto r = c.Post("/api/compare", same);
  ASSERT_EQ(r->status, 200) << r->body;
  const json s = body_json(r);
  EXPECT_NEAR(s["similarity"].get<double>(), 1.0, 1e-6);
  EXPECT_FALSE(s["components"].empty());
  httplib::MultipartFormDataItems different = {{"a", brick, "a.png", "image/png"}, {"b", stripes, "b.png", "image/png"}};
  r = c.Post("/api/compare", different);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_LT(body_json(r)["similarity"].get<double>(), 0.5);  // different textures (docs/metrics.md: 0.1-0.25)
  httplib::MultipartFormDataItems one = {{"a", brick, "a.png", "image/png"}};
  EXPECT_EQ(c.Post("/api/compare", one)->status, 400);
}

TEST_F(Api, DescribesItselfAndServesTheWebUi) {
  RunningServer srv(options());
  auto c = srv.client();
  auto r = c.Get("/api/openapi.json");
  ASSERT_EQ(r->status, 200);
  const json api = body_json(r);
  ASSERT_TRUE(api.is_object());
  EXPECT_EQ(api["openapi"].get<std::string>().substr(0, 2), "3.");
  for (const char* path : {"/api/shaders", "/api/render", "/api/compare", "/api/catalog", "/api/jobs/match", "/api/jobs/morph", "/api/jobs/synth",
                           "/api/jobs/{id}", "/api/jobs/{id}/result", "/api/jobs/{id}/cancel", "/api/jobs/{id}/events"})
    EXPECT_TRUE(api["paths"].contains(path)) << path;
  for (const char* page : {"/", "/library", "/morph", "/synth", "/static/synth.js", "/static/app.js", "/static/app.css"}) {
    r = c.Get(page);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << page;
    EXPECT_EQ(r->body.find("http://"), std::string::npos) << page << " must not load anything from elsewhere";
    EXPECT_EQ(r->body.find("https://"), std::string::npos) << page << " must not load anything from elsewhere";
  }
  r = c.Get("/api/catalog");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_NE(r->body.find("bricks"), std::string::npos);
}

TEST_F(Api, NonLoopbackNeedsATokenAndEveryRequestCarriesIt) {
  auto o = options();
  o.bind = "0.0.0.0";
  EXPECT_THROW(server::Server{o}, UsageError);
  o.bind = "127.0.0.1";
  o.token = "s3cret";
  RunningServer srv(o);
  auto c = srv.client();
  auto r = c.Get("/api/health");
  EXPECT_EQ(r->status, 401);
  EXPECT_TRUE(body_json(r).contains("error"));
  EXPECT_EQ(c.Get("/api/shaders", {{"Authorization", "Bearer wrong"}})->status, 401);
  EXPECT_EQ(c.Get("/", {{"Authorization", "Bearer wrong"}})->status, 401);
  EXPECT_EQ(c.Get("/api/health", {{"Authorization", "Bearer s3cret"}})->status, 200);
  EXPECT_EQ(c.Get("/api/health?token=s3cret")->status, 200);  // EventSource and <img> cannot send headers
}

}  // namespace
}  // namespace proctex
