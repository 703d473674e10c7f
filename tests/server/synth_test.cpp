// Synth jobs through the API (POST /api/jobs/synth) and the retention policy of the job store,
// against a real server on loopback. The service must give what `proctex synth` gives for the
// same exemplar and options (the command line is the reference), record the seed, reuse an
// earlier upload, refuse bad input with 4xx JSON errors, and prune the oldest finished jobs -
// never a running one.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "image/image.h"
#include "tests/server/support.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using namespace proctex::testing;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

class SynthJobs : public ::testing::Test {
 protected:
  // No catalogue: synthesis does not need one.
  server::ServerOptions options() {
    server::ServerOptions o;
    o.port = 0;
    o.catalog = dir_ / "no-catalogue.sqlite";
    o.data = dir_ / "data";
    return o;
  }
  // A `side` px exemplar cut from the brick photo (its top-left corner, scaled by `scale`).
  fs::path exemplar(int side, int scale = 1, const std::string& name = "") {
    const Image photo = load_image(brick_photo());
    const Image cut = crop(photo, 0, 0, std::min(photo.width, side * scale), std::min(photo.height, side * scale));
    const fs::path p = dir_ / (name.empty() ? "exemplar" + std::to_string(side) + ".png" : name);
    save_image(cut.width == side ? cut : resize(cut, side, side), p);
    return p;
  }
  TempDir dir_;
};

httplib::Result post_synth(httplib::Client& c, const std::string& bytes, const json& options) {
  httplib::MultipartFormDataItems items = {{"exemplar", bytes, "../../my exemplar.png", "image/png"},
                                           {"options", options.dump(), "", "application/json"}};
  return c.Post("/api/jobs/synth", items);
}

httplib::Result post_json(httplib::Client& c, const json& body) {
  return c.Post("/api/jobs/synth", body.dump(), "application/json");
}

// Follows the job's progress stream to its end; returns the stages seen and the final event.
json follow(httplib::Client& c, const std::string& id, std::vector<std::string>* stages = nullptr) {
  json done;
  std::string buffer;
  c.Get("/api/jobs/" + id + "/events", [&](const char* d, size_t n) {
    buffer.append(d, n);
    for (size_t end; (end = buffer.find("\n\n")) != std::string::npos;) {
      const std::string block = buffer.substr(0, end);
      buffer.erase(0, end + 2);
      const json data = json::parse(block.substr(block.find("data: ") + 6), nullptr, false);
      if (block.rfind("event: done", 0) == 0) done = data;
      else if (stages && data.contains("progress") && data["progress"].contains("stage")) {
        const std::string s = data["progress"]["stage"];
        if (stages->empty() || stages->back() != s) stages->push_back(s);
      }
    }
    return true;
  });
  return done;
}

Image fetch_image(httplib::Client& c, const std::string& url, const fs::path& scratch) {
  auto r = c.Get(url);
  if (!r || r->status != 200) throw std::runtime_error("GET " + url + " failed");
  const fs::path p = scratch / ("fetched-" + std::to_string(std::hash<std::string>()(url)) + ".png");
  std::ofstream(p, std::ios::binary) << r->body;
  return load_image(p);
}

double mean_abs_diff(const Image& a, const Image& b) {
  double s = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) s += std::abs(a.pixels[i] - b.pixels[i]);
  return s / a.pixels.size();
}

TEST_F(SynthJobs, JobGivesWhatTheCommandLineGivesRecordsTheSeedAndReusesTheUpload) {
  RunningServer srv(options());
  auto c = srv.client(120);
  const fs::path ex = exemplar(128, 2);
  auto r = post_synth(c, slurp(ex), {{"size", 256}, {"seed", 7}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id = body_json(r)["id"];
  EXPECT_EQ(r->get_header_value("Location"), "/api/jobs/" + id);
  std::vector<std::string> stages;
  const json done = follow(c, id, &stages);
  ASSERT_EQ(done.value("state", ""), "done") << done.dump();
  // The stream carries the latest progress (a fast job's "synthesis" can be overtaken by its end):
  // what was seen is progress, in the job's order of stages.
  const std::vector<std::string> order = {"exemplar", "analysis", "synthesis", "done"};
  ASSERT_FALSE(stages.empty());
  size_t last = 0;
  for (const auto& s : stages) {
    const size_t at = std::find(order.begin(), order.end(), s) - order.begin();
    ASSERT_LT(at, order.size()) << json(stages).dump();
    EXPECT_GE(at, last) << json(stages).dump();
    last = at;
  }

  // The seed is recorded in the job (its parameters) and in the result.
  const json job = body_json(c.Get("/api/jobs/" + id));
  EXPECT_EQ(job["kind"], "synth");
  EXPECT_EQ(job["params"]["options"]["seed"], 7);
  const json result = body_json(c.Get("/api/jobs/" + id + "/result"));
  EXPECT_EQ(result["seed"], 7);
  EXPECT_EQ(result["size"], json::array({256, 256}));
  EXPECT_EQ(result["exemplar"]["width"], 128);
  EXPECT_GT(result["timings"]["synthesis"].get<double>(), 0.0);

  // The same pixels as the command line with the same exemplar and options.
  const Image served = fetch_image(c, "/api/jobs/" + id + "/files/synth.png", dir_.path());
  ASSERT_EQ(served.width, 256);
  ASSERT_EQ(served.height, 256);
  const auto cli = run_proctex("synth '" + ex.string() + "' -o '" + (dir_ / "cli.png").string() +
                                   "' --size 256 --seed 7 --cache-dir '" + (dir_ / "cli-cache").string() + "'",
                               dir_.path());
  ASSERT_EQ(cli.exit_code, 0) << cli.err;
  EXPECT_EQ(served.pixels, load_image(dir_ / "cli.png").pixels) << "the service and `proctex synth` differ";
  // The exemplar actually used is downloadable, and is the upload.
  EXPECT_EQ(fetch_image(c, "/api/jobs/" + id + "/files/exemplar.png", dir_.path()).pixels, load_image(ex).pixels);

  // Another seed on the same upload (no second upload): another texture, the same statistics.
  r = post_json(c, {{"from_job", id}, {"size", 256}, {"seed", 8}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id2 = body_json(r)["id"];
  ASSERT_EQ(follow(c, id2).value("state", ""), "done");
  const json result2 = body_json(c.Get("/api/jobs/" + id2 + "/result"));
  EXPECT_EQ(result2["seed"], 8);
  EXPECT_EQ(result2["analysis_cached"], true) << "the analysis of the same exemplar is cached";
  const Image other = fetch_image(c, "/api/jobs/" + id2 + "/files/synth.png", dir_.path());
  EXPECT_GT(mean_abs_diff(served, other), 0.02) << "seed 8 gave (nearly) the picture of seed 7";

  // Tileable: the command line's tileable output, and a seam at the wrap no larger than steps inside.
  r = post_json(c, {{"from_job", id}, {"size", 128}, {"tileable", true}, {"seed", 3}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id3 = body_json(r)["id"];
  ASSERT_EQ(follow(c, id3).value("state", ""), "done");
  const Image tile = fetch_image(c, "/api/jobs/" + id3 + "/files/synth.png", dir_.path());
  const auto cli_tile = run_proctex("synth '" + ex.string() + "' -o '" + (dir_ / "cli-tile.png").string() +
                                        "' --size 128 --tileable --seed 3 --no-cache",
                                    dir_.path());
  ASSERT_EQ(cli_tile.exit_code, 0) << cli_tile.err;
  EXPECT_EQ(tile.pixels, load_image(dir_ / "cli-tile.png").pixels);
  auto column_step = [&](int a, int b) {
    double s = 0;
    for (int y = 0; y < tile.height; ++y)
      for (int k = 0; k < 3; ++k) s += std::abs(tile.pixel(a, y)[k] - tile.pixel(b, y)[k]);
    return s / tile.height;
  };
  std::vector<double> inner;
  for (int x = 0; x + 1 < tile.width; ++x) inner.push_back(column_step(x, x + 1));
  std::sort(inner.begin(), inner.end());
  EXPECT_LE(column_step(tile.width - 1, 0), inner[inner.size() * 95 / 100]) << "a seam at the wrap";

  // A 600 px wide photo is scaled down to 512 when asked to, and refused otherwise (next test).
  // (600x48: a cheap analysis.)
  const fs::path big = dir_ / "wide.png";
  save_image(resize(crop(load_image(brick_photo()), 0, 0, 500, 40), 600, 48), big);
  r = post_synth(c, slurp(big), {{"size", 64}, {"downscale", true}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id4 = body_json(r)["id"];
  ASSERT_EQ(follow(c, id4).value("state", ""), "done");
  const json result4 = body_json(c.Get("/api/jobs/" + id4 + "/result"));
  EXPECT_EQ(result4["exemplar"]["width"], 512);
  EXPECT_EQ(result4["exemplar"]["height"], 41);  // 48 * 512 / 600, rounded
  EXPECT_EQ(result4["exemplar"]["uploaded"], json::array({600, 48}));
  EXPECT_EQ(result4["exemplar"]["downscaled"], true);
}

TEST_F(SynthJobs, CancelStopsAJobWithoutLeavingAPartialFile) {
  auto o = options();
  o.max_synth_size = 4096;
  RunningServer srv(o);
  auto c = srv.client(120);
  const std::string bytes = slurp(exemplar(128, 2));
  auto r = post_synth(c, bytes, {{"size", 4096}});  // ~10 s of synthesis in 16 strips
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string running = body_json(r)["id"];
  r = post_synth(c, bytes, {{"size", 64}});
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string queued = body_json(r)["id"];
  wait_for(c, running, [](const json& s) { return s["progress"].value("stage", "") == "synthesis"; }, 60);

  r = c.Post("/api/jobs/" + queued + "/cancel");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(body_json(r)["state"], "cancelled");
  r = c.Post("/api/jobs/" + running + "/cancel");
  ASSERT_EQ(r->status, 200) << r->body;
  const json after = body_json(r);
  EXPECT_EQ(after["state"], "cancelled") << after.dump();
  EXPECT_TRUE(after["result"].is_null());
  EXPECT_EQ(c.Get("/api/jobs/" + running + "/result")->status, 409);
  // Nothing half-written in the job's folder: its input and the exemplar, no synth.png, no temporaries.
  for (const auto& e : fs::directory_iterator(dir_ / "data" / "jobs" / running)) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name == "input.png" || name == "exemplar.png") << "left behind: " << name;
  }
  // A retry runs the cancelled queued job from its stored parameters and upload.
  r = c.Post("/api/jobs/" + queued + "/retry");
  ASSERT_EQ(r->status, 202) << r->body;
  ASSERT_EQ(follow(c, queued).value("state", ""), "done");
  EXPECT_EQ(fetch_image(c, "/api/jobs/" + queued + "/files/synth.png", dir_.path()).width, 64);
  EXPECT_EQ(c.Get("/api/health")->status, 200);
}

TEST_F(SynthJobs, BadRequestsGet4xxJsonErrorsAndLeaveNothingBehind) {
  auto o = options();
  o.max_upload_dimension = 4096;
  RunningServer srv(o);
  auto c = srv.client(60);
  const std::string ok = slurp(exemplar(64));
  const std::string tiny = slurp(exemplar(8));
  const std::string big = slurp(exemplar(600, 1, "big.png"));
  std::string truncated = ok.substr(0, ok.size() / 2);

  // A valid upload first, to name in from_job.
  auto r = post_synth(c, ok, {{"size", 64}});
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string good = body_json(r)["id"];
  ASSERT_EQ(follow(c, good).value("state", ""), "done");

  struct Case {
    std::string what;
    std::function<httplib::Result()> send;
    int status;
    std::string mentions;  // a word the error must contain
  };
  const std::vector<Case> cases = {
      {"not an image", [&] { return post_synth(c, "hello, I am text", json::object()); }, 415, "not a PNG"},
      {"truncated PNG", [&] { return post_synth(c, truncated, json::object()); }, 400, "cannot be read"},
      {"8 px exemplar", [&] { return post_synth(c, tiny, json::object()); }, 400, "at least 16"},
      {"600 px exemplar", [&] { return post_synth(c, big, json::object()); }, 400, "512"},
      {"size 100000", [&] { return post_synth(c, ok, {{"size", 100000}}); }, 400, "size"},
      {"size 0", [&] { return post_synth(c, ok, {{"size", 0}}); }, 400, "size"},
      {"size 4.5", [&] { return post_synth(c, ok, {{"size", 4.5}}); }, 400, "size"},
      {"size abc", [&] { return post_synth(c, ok, {{"size", "abc"}}); }, 400, "size"},
      {"size [16]", [&] { return post_synth(c, ok, {{"size", json::array({16})}}); }, 400, "size"},
      {"odd tileable", [&] { return post_synth(c, ok, {{"size", 255}, {"tileable", true}}); }, 400, "even"},
      {"tileable as text", [&] { return post_synth(c, ok, {{"tileable", "yes"}}); }, 400, "tileable"},
      {"negative randomness", [&] { return post_synth(c, ok, {{"randomness", -1}}); }, 400, "randomness"},
      {"randomness text", [&] { return post_synth(c, ok, {{"randomness", "lots"}}); }, 400, "randomness"},
      {"randomness per level, too many", [&] { return post_synth(c, ok, {{"randomness", std::vector<double>(12, 0.5)}}); }, 400, "levels"},
      {"seed -1", [&] { return post_synth(c, ok, {{"seed", -1}}); }, 400, "seed"},
      {"seed 2^33", [&] { return post_synth(c, ok, {{"seed", int64_t(1) << 33}}); }, 400, "seed"},
      {"passes 99", [&] { return post_synth(c, ok, {{"passes", 99}}); }, 400, "passes"},
      {"unknown option", [&] { return post_synth(c, ok, {{"colour", "red"}}); }, 400, "unknown"},
      {"options not JSON", [&] {
         httplib::MultipartFormDataItems items = {{"exemplar", ok, "e.png", "image/png"}, {"options", "{size:", "", ""}};
         return c.Post("/api/jobs/synth", items);
       }, 400, "JSON"},
      {"no exemplar", [&] { return post_json(c, {{"size", 64}}); }, 400, "exemplar"},
      {"body not JSON", [&] { return c.Post("/api/jobs/synth", "size=64", "application/x-www-form-urlencoded"); }, 400, "JSON"},
      {"unknown from_job", [&] { return post_json(c, {{"from_job", std::string(32, 'a')}}); }, 404, "no job"},
      {"from_job a path", [&] { return post_json(c, {{"from_job", "../../etc/passwd"}}); }, 400, "from_job"},
      {"upload and from_job", [&] { return post_synth(c, ok, {{"from_job", good}}); }, 400, "both"},
  };
  const auto jobs_before = body_json(c.Get("/api/jobs"))["jobs"].size();
  for (const auto& k : cases) {
    auto res = k.send();
    ASSERT_TRUE(res) << k.what;
    EXPECT_EQ(res->status, k.status) << k.what << ": " << res->body;
    const json err = body_json(res);
    ASSERT_TRUE(err.is_object() && err.contains("error")) << k.what << ": " << res->body;
    EXPECT_NE(err["error"].get<std::string>().find(k.mentions), std::string::npos)
        << k.what << ": '" << err["error"] << "' should mention '" << k.mentions << "'";
    EXPECT_EQ(err["status"], k.status) << k.what;
  }
  EXPECT_EQ(body_json(c.Get("/api/jobs"))["jobs"].size(), jobs_before) << "a refused request created a job";
  EXPECT_TRUE(fs::is_empty(dir_ / "data" / "tmp")) << "an upload was left in DATA/tmp";
  EXPECT_EQ(c.Get("/api/health")->status, 200);

  // The image as the raw body, options in the query (as for match): accepted.
  r = c.Post("/api/jobs/synth?options=%7B%22size%22%3A%2032%2C%20%22seed%22%3A%205%7D", ok, "image/png");
  ASSERT_EQ(r->status, 202) << r->body;
  EXPECT_EQ(body_json(r)["params"]["options"]["seed"], 5);
  EXPECT_EQ(body_json(r)["params"]["options"]["size"], json::array({32, 32}));
}

// Sorted ids of the jobs the server lists.
std::vector<std::string> listed(httplib::Client& c) {
  std::vector<std::string> ids;
  const json all = body_json(c.Get("/api/jobs"));
  EXPECT_TRUE(all.is_object() && all.contains("jobs")) << all.dump();
  for (const auto& j : all["jobs"]) ids.push_back(j["id"]);
  std::sort(ids.begin(), ids.end());
  return ids;
}

// The retention runs on the worker right after a job's "done": wait a little for it.
std::vector<std::string> listed_once_pruned(httplib::Client& c, const std::vector<std::string>& expect) {
  std::vector<std::string> ids;
  for (int i = 0; i < 50; ++i) {
    ids = listed(c);
    if (ids == expect) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return ids;
}

uint64_t tree_bytes(const fs::path& dir) {
  uint64_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) n += e.file_size();
  return n;
}

TEST_F(SynthJobs, RetentionDeletesTheOldestFinishedJobsFirstAtStartAndAfterJobs) {
  const std::string bytes = slurp(exemplar(64));
  std::vector<std::string> ids;  // oldest first
  {
    auto o = options();
    o.keep_jobs = 0;
    o.max_data_bytes = 0;
    RunningServer srv(o);
    auto c = srv.client(60);
    for (int seed = 1; seed <= 4; ++seed) {
      auto r = post_synth(c, bytes, {{"size", 96}, {"seed", seed}});
      ASSERT_EQ(r->status, 202) << r->body;
      ids.push_back(body_json(r)["id"]);
      ASSERT_EQ(follow(c, ids.back()).value("state", ""), "done");
      std::this_thread::sleep_for(std::chrono::milliseconds(20));  // distinct finish times
    }
  }
  const fs::path jobs = dir_ / "data" / "jobs", cache = dir_ / "data" / "cache" / "synth";
  ASSERT_FALSE(fs::is_empty(cache)) << "the analysis is cached under DATA/cache/synth";
  // A size limit that holds the two newest jobs but not also the cache or a third job.
  {
    auto o = options();
    o.keep_jobs = 0;
    o.max_data_bytes = tree_bytes(jobs / ids[2]) + tree_bytes(jobs / ids[3]) + 512;
    ASSERT_LT(o.max_data_bytes, tree_bytes(jobs / ids[1]) + tree_bytes(jobs / ids[2]) + tree_bytes(jobs / ids[3]));
    RunningServer srv(o);
    auto c = srv.client(60);
    std::vector<std::string> expect = {ids[2], ids[3]};
    std::sort(expect.begin(), expect.end());
    EXPECT_EQ(listed(c), expect) << "a start-up prune keeps the two newest";
    EXPECT_FALSE(fs::exists(jobs / ids[0]));
    EXPECT_FALSE(fs::exists(jobs / ids[1]));
    EXPECT_TRUE(fs::is_empty(cache)) << "the re-computable cache goes before any job";
    EXPECT_EQ(c.Get("/api/jobs/" + ids[0])->status, 404);
    EXPECT_EQ(c.Get("/api/jobs/" + ids[3] + "/files/synth.png")->status, 200);
    const json health = body_json(c.Get("/api/health"));
    EXPECT_EQ(health["retention"]["jobs_pruned"], 2);
    EXPECT_LE(health["retention"]["data_bytes"].get<uint64_t>(), o.max_data_bytes);
  }
  // --keep-jobs 1 while a job runs: the running job (older than the one that finishes) is never
  // deleted; when it finishes it is the newest and the other goes.
  {
    auto o = options();
    o.keep_jobs = 1;
    o.max_data_bytes = 0;
    o.workers = 2;
    RunningServer srv(o);
    auto c = srv.client(120);
    EXPECT_EQ(listed(c), std::vector<std::string>{ids[3]});
    auto r = post_synth(c, bytes, {{"size", 2048}, {"seed", 9}});  // a few seconds
    ASSERT_EQ(r->status, 202) << r->body;
    const std::string slow = body_json(r)["id"];
    wait_for(c, slow, [](const json& s) { return s.value("state", "") == "running"; }, 30);
    r = post_synth(c, bytes, {{"size", 64}, {"seed", 10}});
    ASSERT_EQ(r->status, 202) << r->body;
    const std::string quick = body_json(r)["id"];
    const json q = follow(c, quick);
    ASSERT_EQ(q.value("state", ""), "done");
    const json s = body_json(c.Get("/api/jobs/" + slow));
    if (s.value("state", "") == "running") {  // the usual case: the quick job finished first
      std::vector<std::string> expect = {quick, slow};
      std::sort(expect.begin(), expect.end());
      EXPECT_EQ(listed_once_pruned(c, expect), expect) << "the running job stays; the older finished one goes";
    }
    ASSERT_EQ(follow(c, slow).value("state", ""), "done");
    EXPECT_EQ(c.Get("/api/jobs/" + slow + "/files/synth.png")->status, 200);
    EXPECT_EQ(listed_once_pruned(c, {slow}), std::vector<std::string>{slow});
    EXPECT_FALSE(fs::exists(jobs / quick));
    EXPECT_FALSE(fs::exists(jobs / ids[3]));
  }
}

}  // namespace
}  // namespace proctex
