// Match and morph jobs through the API: progress stream, results and files, cancel (best so far),
// a restart that keeps finished results and marks interrupted jobs, and a bounded load test.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>

#include "tests/server/support.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using namespace proctex::testing;
using nlohmann::json;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

class Jobs : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { catalog_ = new fs::path(test_catalog()); }
  static void TearDownTestSuite() { delete catalog_; }
  server::ServerOptions options() {
    server::ServerOptions o;
    o.port = 0;
    o.catalog = *catalog_;
    o.data = dir_ / "data";
    return o;
  }
  static fs::path* catalog_;
  TempDir dir_;
};
fs::path* Jobs::catalog_ = nullptr;

struct Event {
  std::string name;
  json data;
  double at = 0;  // seconds since the stream opened
};

// Reads a Server-Sent Events stream to its end.
std::vector<Event> read_events(httplib::Client& c, const std::string& path) {
  std::vector<Event> events;
  std::string buffer;
  const auto t0 = Clock::now();
  auto r = c.Get(path, [&](const char* data, size_t n) {
    buffer.append(data, n);
    for (size_t end; (end = buffer.find("\n\n")) != std::string::npos;) {
      const std::string block = buffer.substr(0, end);
      buffer.erase(0, end + 2);
      Event e;
      e.at = since(t0);
      std::istringstream lines(block);
      for (std::string line; std::getline(lines, line);) {
        if (line.rfind("event: ", 0) == 0) e.name = line.substr(7);
        if (line.rfind("data: ", 0) == 0) e.data = json::parse(line.substr(6), nullptr, false);
      }
      events.push_back(e);
    }
    return true;
  });
  EXPECT_TRUE(r);
  if (r) {
    EXPECT_EQ(r->get_header_value("Content-Type"), "text/event-stream");
  }
  return events;
}

TEST_F(Jobs, MatchStreamsProgressAndPreviewsThenGivesTheResultAndItsFiles) {
  RunningServer srv(options());
  auto c = srv.client(120);
  const auto t0 = Clock::now();
  auto r = post_match(c, slurp(brick_photo()), {{"budget", "4s"}});
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const json created = body_json(r);
  const std::string id = created["id"];
  EXPECT_EQ(r->get_header_value("Location"), "/api/jobs/" + id);
  EXPECT_EQ(created["kind"], "match");

  const auto events = read_events(c, "/api/jobs/" + id + "/events");
  ASSERT_GE(events.size(), 2u);
  EXPECT_EQ(events.back().name, "done");
  int previews = 0;
  double first_preview = -1, prev_best = 0;
  std::vector<double> running_times;
  std::set<std::string> stages;
  for (const auto& e : events) {
    if (e.name != "progress") continue;
    if (e.data["state"] == "running") running_times.push_back(e.at);
    const json& p = e.data["progress"];
    if (p.contains("stage")) stages.insert(p["stage"].get<std::string>().substr(0, 4));
    if (e.data.contains("preview")) {
      ++previews;
      if (first_preview < 0) first_preview = e.at;
      EXPECT_EQ(e.data["preview"].get<std::string>().rfind("data:image/png;base64,", 0), 0u);
    }
    if (p.contains("best") && p.value("stage", "") != "done") {  // "done": the final full-resolution score
      EXPECT_GE(p["best"].get<double>(), prev_best - 1e-12) << "the best similarity so far never drops";
      prev_best = p["best"].get<double>();
    }
  }
  EXPECT_GE(previews, 2) << "the preview follows the best match";
  // The global search shows as "global" and, when its screening ends, "screened" (one may fall
  // between two samples of the stream).
  EXPECT_TRUE((stages.count("glob") || stages.count("scre")) && stages.count("race")) << "stages are reported: " << ::testing::PrintToString(stages);
  // At least twice a second while the match runs.
  ASSERT_GE(running_times.size(), 2u);
  const double span = running_times.back() - running_times.front();
  EXPECT_GE((running_times.size() - 1) / std::max(span, 1e-9), 2.0);
  std::printf("first preview %.2f s after the stream opened (%.2f s after the upload), %d previews, %zu progress events in %.1f s\n",
              first_preview, first_preview + 0.0, previews, running_times.size(), span);
  (void)t0;

  const json done = events.back().data;
  EXPECT_EQ(done["state"], "done");
  const json result = done["result"];
  EXPECT_EQ(result["spec"]["shader"], "bricks") << "the brick photo matches bricks among bricks/stripes/clouds";
  EXPECT_GT(result["similarity"].get<double>(), 0.25);
  EXPECT_TRUE(result.contains("verdict"));

  r = c.Get("/api/jobs/" + id + "/result");
  ASSERT_EQ(r->status, 200);
  EXPECT_EQ(body_json(r)["spec"], result["spec"]);
  for (const auto& [what, file] : result["files"].items()) {
    auto f = c.Get("/api/jobs/" + id + "/files/" + file.get<std::string>());
    ASSERT_TRUE(f);
    EXPECT_EQ(f->status, 200) << what;
    EXPECT_FALSE(f->body.empty()) << what;
  }
  const std::string render = c.Get("/api/jobs/" + id + "/files/render.png")->body;
  EXPECT_EQ(render.substr(1, 3), "PNG");
  // The spec file is the result's spec, usable with proctex render.
  EXPECT_EQ(json::parse(c.Get("/api/jobs/" + id + "/files/spec.json")->body), result["spec"]);
  // The events of a finished job: one "done" at once.
  const auto again = read_events(c, "/api/jobs/" + id + "/events");
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].name, "done");
}

TEST_F(Jobs, RestartKeepsResultsMarksInterruptedJobsAndRetryAndCancelWork) {
  std::string done_id, running_id, queued_id;
  json done_result;
  {
    RunningServer srv(options());
    auto c = srv.client(120);
    done_id = body_json(post_match(c, slurp(brick_photo()), {{"budget", 60}, {"race", 2}, {"starts", 1}}))["id"];
    const json s = wait_for(c, done_id, finished, 90);
    ASSERT_EQ(s["state"], "done") << s.dump();
    done_result = body_json(c.Get("/api/jobs/" + done_id + "/result"));
    running_id = body_json(post_match(c, slurp(brick_photo()), {{"budget", "30s"}}))["id"];
    queued_id = body_json(post_match(c, slurp(brick_photo()), {{"budget", "30s"}}))["id"];
    const json r = wait_for(c, running_id, [](const json& j) { return j["state"] == "running"; });
    ASSERT_EQ(r["state"], "running");
    EXPECT_EQ(body_json(c.Get("/api/jobs/" + queued_id))["state"], "queued");
    srv.shutdown();  // as if the service were restarted while a job runs
  }
  RunningServer srv(options());
  auto c = srv.client(120);
  json s = body_json(c.Get("/api/jobs/" + done_id));
  EXPECT_EQ(s["state"], "done");
  EXPECT_EQ(body_json(c.Get("/api/jobs/" + done_id + "/result")), done_result);
  EXPECT_EQ(c.Get("/api/jobs/" + done_id + "/files/render.png")->status, 200);
  EXPECT_EQ(body_json(c.Get("/api/jobs/" + running_id))["state"], "interrupted");
  EXPECT_EQ(body_json(c.Get("/api/jobs/" + queued_id))["state"], "interrupted");
  EXPECT_EQ(c.Get("/api/jobs/" + running_id + "/result")->status, 409);
  EXPECT_EQ(c.Post("/api/jobs/" + done_id + "/retry")->status, 409);

  // Re-run an interrupted job, then stop it: the answer is the best match so far.
  auto r = c.Post("/api/jobs/" + queued_id + "/retry");
  ASSERT_EQ(r->status, 202) << r->body;
  s = wait_for(c, queued_id, [](const json& j) { return j["progress"].value("best", 0.0) > 0; });
  ASSERT_EQ(s["state"], "running") << s.dump();
  const auto t_cancel = Clock::now();
  r = c.Post("/api/jobs/" + queued_id + "/cancel");
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_LT(since(t_cancel), 15.0) << "a cancel answers promptly";
  const json cancelled = body_json(r);
  EXPECT_EQ(cancelled["state"], "cancelled");
  ASSERT_TRUE(cancelled["result"].is_object());
  EXPECT_TRUE(cancelled["result"]["stopped_early"].get<bool>());
  EXPECT_FALSE(cancelled["result"]["spec"]["shader"].get<std::string>().empty());
  EXPECT_EQ(c.Post("/api/jobs/" + queued_id + "/cancel")->status, 409);  // nothing left to cancel
}

TEST_F(Jobs, BoundedLoadOnlyDocumented429sAndBoundedMemory) {
  auto o = options();
  o.queue_limit = 4;
  RunningServer srv(o);
  std::atomic<bool> stop{false};
  std::atomic<int> polls{0}, poll_errors{0};
  std::mutex m;
  std::vector<std::string> ids;
  std::vector<std::thread> pollers;
  for (int i = 0; i < 50; ++i)
    pollers.emplace_back([&, i] {
      auto c = srv.client(30);
      c.set_keep_alive(i % 2 == 0);  // half keep their connection (browsers), half open one per request
      while (!stop) {
        std::string id;
        {
          std::lock_guard lock(m);
          if (!ids.empty()) id = ids[i % ids.size()];
        }
        auto r = c.Get(id.empty() ? "/api/health" : "/api/jobs/" + id);
        ++polls;
        if (!r || r->status != 200 || !body_json(r).is_object()) {
          ++poll_errors;
          if (!r) std::fprintf(stderr, "poll failed: %s\n", httplib::to_string(r.error()).c_str());
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    });
  auto c = srv.client(60);
  const std::string photo = slurp(brick_photo());
  int accepted = 0, rejected = 0, other = 0;
  for (int i = 0; i < 10; ++i) {
    auto r = post_match(c, photo, {{"budget", 40}, {"race", 2}, {"starts", 1}});
    EXPECT_TRUE(r) << httplib::to_string(r.error());
    if (!r) {
      ++other;
      continue;
    }
    if (r->status == 202) {
      ++accepted;
      std::lock_guard lock(m);
      ids.push_back(body_json(r)["id"]);
    } else if (r->status == 429) {
      ++rejected;
      EXPECT_TRUE(body_json(r).contains("error"));
      EXPECT_FALSE(r->get_header_value("Retry-After").empty());
    } else {
      ++other;
      ADD_FAILURE() << r->status << " " << r->body;
    }
  }
  // 1 running + 4 waiting (or 4 waiting before the first one started), the rest refused.
  EXPECT_GE(accepted, 4);
  EXPECT_LE(accepted, 6);
  EXPECT_EQ(accepted + rejected, 10) << other << " failed";
  EXPECT_EQ(other, 0);
  for (const auto& id : ids) {
    const json s = wait_for(c, id, finished, 120);
    EXPECT_EQ(s["state"], "done") << s.dump();
  }
  stop = true;
  for (auto& t : pollers) t.join();
  EXPECT_EQ(poll_errors.load(), 0) << "of " << polls.load() << " polls";
  EXPECT_GT(polls.load(), 200);
  // Peak memory of this process (server, jobs and 50 clients): under 1 GB.
  std::ifstream status("/proc/self/status");
  long hwm_kb = 0;
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmHWM:", 0) == 0) hwm_kb = std::stol(line.substr(6));
  std::printf("%d polls, %d accepted, %d refused (429), peak RSS %.0f MB\n", polls.load(), accepted, rejected, hwm_kb / 1024.0);
  EXPECT_LT(hwm_kb, 1024 * 1024);
}

TEST_F(Jobs, MorphJobWritesFramesGifAndFilmstrip) {
  RunningServer srv(options());
  auto c = srv.client(120);
  auto r = c.Post("/api/jobs/morph",
                  R"({"keys": [{"shader": "stripes", "params": {"duty": 0.2}, "seed": 2}, "stripes:duty=0.8,seed=2"],
                      "frames": 6, "size": 64, "fps": 6})",
                  "application/json");
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string id = body_json(r)["id"];
  const json s = wait_for(c, id, finished, 90);
  ASSERT_EQ(s["state"], "done") << s.dump();
  const json result = body_json(c.Get("/api/jobs/" + id + "/result"));
  ASSERT_EQ(result["files"]["frames"].size(), 6u);
  auto gif = c.Get("/api/jobs/" + id + "/files/morph.gif");
  ASSERT_EQ(gif->status, 200);
  EXPECT_EQ(gif->body.substr(0, 4), "GIF8");
  EXPECT_EQ(c.Get("/api/jobs/" + id + "/files/filmstrip.png")->status, 200);
  EXPECT_EQ(c.Get("/api/jobs/" + id + "/files/" + result["files"]["frames"][5].get<std::string>())->status, 200);
  // Bad morphs: one key, an unknown shader, absurd frame counts.
  EXPECT_EQ(c.Post("/api/jobs/morph", R"({"keys": ["stripes"]})", "application/json")->status, 400);
  EXPECT_EQ(c.Post("/api/jobs/morph", R"({"keys": ["stripes", "nosuch"]})", "application/json")->status, 400);
  EXPECT_EQ(c.Post("/api/jobs/morph", R"({"keys": ["stripes", "stripes:duty=0.7"], "frames": 1000000})", "application/json")->status, 400);
}

}  // namespace
}  // namespace proctex
