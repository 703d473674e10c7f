// Hostile uploads and parameters: every one gets a 4xx with a JSON error saying what is wrong,
// nothing is written outside --data (nor left in its tmp/), client file names are never paths,
// and the server keeps serving.
#include <gtest/gtest.h>

#include <zlib.h>

#include "tests/server/support.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using namespace proctex::testing;
using nlohmann::json;

std::string be32(uint32_t v) {
  return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
  const std::string body = type + data;
  const uint32_t crc = crc32(0, reinterpret_cast<const Bytef*>(body.data()), body.size());
  return be32(data.size()) + body + be32(crc);
}

// A well-formed PNG that declares width x height and carries almost no data: decoding it would
// allocate the whole declared image (a decompression bomb when the sides are huge).
std::string declared_png(uint32_t width, uint32_t height) {
  std::string ihdr = be32(width) + be32(height) + std::string("\x08\x02\x00\x00\x00", 5);
  // The pixel rows of small images (filters + RGB), a few bytes for the huge ones.
  const uint64_t rows = uint64_t(height) * (1 + 3 * uint64_t(width));
  std::string raw(rows <= 100000 ? rows : 64, '\0');
  uLongf n = compressBound(raw.size());
  std::string z(n, '\0');
  compress(reinterpret_cast<Bytef*>(z.data()), &n, reinterpret_cast<const Bytef*>(raw.data()), raw.size());
  z.resize(n);
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", z) + png_chunk("IEND", "");
}

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { catalog_ = new fs::path(test_catalog()); }
  static void TearDownTestSuite() { delete catalog_; }
  static fs::path* catalog_;
  TempDir dir_;
};
fs::path* BadInput::catalog_ = nullptr;

TEST_F(BadInput, UploadsAndOptionsGet4xxWithJsonErrorsAndNothingIsWrittenOutsideData) {
  server::ServerOptions o;
  o.port = 0;
  o.catalog = *catalog_;
  o.data = dir_ / "data";
  o.max_upload_bytes = 1u << 20;
  o.max_upload_dimension = 4096;
  const fs::path cwd = fs::current_path();
  std::set<std::string> cwd_before;
  for (const auto& e : fs::directory_iterator(cwd)) cwd_before.insert(e.path().filename().string());
  RunningServer srv(o);
  auto c = srv.client(60);
  const std::string brick = slurp(brick_photo());

  struct Case {
    std::string what;
    std::string bytes;
    json options;
    int status;
    std::string mentions;
  };
  const std::vector<Case> cases = {
      {"text, not an image", "hello, this is not an image", json::object(), 415, "not a PNG"},
      {"empty file", "", json::object(), 400, "empty"},
      {"truncated PNG", brick.substr(0, brick.size() / 3), json::object(), 400, "photo"},
      {"decompression bomb", declared_png(100000, 100000), json::object(), 400, "100000"},
      {"too big for this server", declared_png(5000, 5000), json::object(), 400, "5000"},
      {"tiny image", declared_png(8, 8), json::object(), 400, "8x8"},
      {"oversized upload", std::string("\x89PNG\r\n\x1a\n", 8) + std::string(1200000, 'x'), json::object(), 413, "too large"},
      {"unknown shader", brick, {{"shaders", {"brickz"}}}, 400, "brickz"},
      {"unknown option", brick, {{"colour", "red"}}, 400, "colour"},
      {"bad budget", brick, {{"budget", "soon"}}, 400, "budget"},
      {"negative evaluations", brick, {{"evaluations", -3}}, 400, "evaluations"},
      {"wrong type", brick, {{"race", "many"}}, 400, "race"},
      {"bad crop", brick, {{"crop", "0,0,10"}}, 400, "crop"},
      {"options not an object", brick, json::array({1, 2}), 400, "object"},
  };
  for (const auto& k : cases) {
    auto r = post_match(c, k.bytes, k.options);
    ASSERT_TRUE(r) << k.what;
    EXPECT_EQ(r->status, k.status) << k.what << ": " << r->body;
    const json j = body_json(r);
    ASSERT_TRUE(j.is_object()) << k.what << ": " << r->body;
    EXPECT_NE(j.value("error", "").find(k.mentions), std::string::npos) << k.what << ": " << r->body;
  }
  // Malformed JSON options, and a client file name that tries to escape.
  httplib::MultipartFormDataItems items = {{"photo", brick, "../../../../tmp/evil.png", "image/png"},
                                           {"options", "{budget: 3", "", "application/json"}};
  auto r = c.Post("/api/jobs/match", items);
  EXPECT_EQ(r->status, 400);
  EXPECT_NE(body_json(r).value("error", "").find("JSON"), std::string::npos) << r->body;
  items[1].content = R"({"budget": 5, "race": 1, "starts": 1})";
  r = c.Post("/api/jobs/match", items);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id = body_json(r)["id"];
  EXPECT_EQ(wait_for(c, id, finished, 60)["state"], "done");
  EXPECT_FALSE(fs::exists("/tmp/evil.png"));
  EXPECT_TRUE(fs::exists(o.data / "jobs" / id / "input.png")) << "uploads are stored under a server-chosen name";

  // Unknown jobs and files, path tricks.
  for (const std::string& path : std::vector<std::string>{"/api/jobs/0123456789abcdef0123456789abcdef", "/api/jobs/../../etc/passwd",
                                 "/api/jobs/" + id + "/files/../../jobs.sqlite", "/api/jobs/" + id + "/files/%2e%2e/jobs.sqlite",
                                 "/api/jobs/" + id + "/files/nothere.png", "/api/jobs/x/result"}) {
    r = c.Get(path);
    ASSERT_TRUE(r) << path;
    EXPECT_GE(r->status, 400) << path;
    EXPECT_LT(r->status, 500) << path;
    EXPECT_TRUE(body_json(r).is_object()) << path << ": " << r->body;
  }
  EXPECT_EQ(c.Post("/api/jobs/0123456789abcdef0123456789abcdef/cancel")->status, 404);

  // Still serving, tmp/ left empty, nothing new beside the data folder.
  EXPECT_EQ(c.Get("/api/health")->status, 200);
  EXPECT_TRUE(fs::is_empty(o.data / "tmp"));
  for (const auto& e : fs::recursive_directory_iterator(o.data)) {
    const std::string rel = fs::relative(e.path(), o.data).string();
    // The store, the jobs' folders, tmp/ and the (empty: no synth ran) synth analysis cache.
    EXPECT_TRUE(rel.rfind("jobs", 0) == 0 || rel == "tmp" || rel == "cache" || rel == "cache/synth") << rel;
  }
  std::set<std::string> cwd_after;
  for (const auto& e : fs::directory_iterator(cwd)) cwd_after.insert(e.path().filename().string());
  EXPECT_EQ(cwd_before, cwd_after);
}

TEST_F(BadInput, WithoutACatalogueMatchAnswers503AndRendersStillWork) {
  server::ServerOptions o;
  o.port = 0;
  o.catalog = dir_ / "missing.sqlite";
  o.data = dir_ / "data";
  RunningServer srv(o);
  auto c = srv.client();
  auto r = post_match(c, slurp(brick_photo()), json::object());
  EXPECT_EQ(r->status, 503);
  EXPECT_NE(body_json(r).value("hint", "").find("--db"), std::string::npos);
  EXPECT_EQ(c.Post("/api/render", R"({"spec": "stripes", "size": 32})", "application/json")->status, 200);
}

}  // namespace
}  // namespace proctex
