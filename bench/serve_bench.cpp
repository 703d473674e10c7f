// bench_serve: the speed targets of proctex serve (issue 15), against a real server on loopback.
//   bench_serve [--db CATALOG] [--photo PHOTO] [--renders 30] [--runs 3] [--markdown FILE]
//   1. slider renders: POST /api/render of a 256^2 bricks spec (a new `rows` each time, as a
//      slider move), end to end from the client, idle and while a match job runs (target < 150 ms),
//      the latter with the server's UI-render priority (a match pauses between batches while a
//      render waits) and, for comparison, without it (a second server);
//   2. first live preview: from the start of the upload to the first SSE event carrying a preview
//      (target < 2 s);
//   3. service overhead: wall time of a match job (upload -> "done" event, result files written)
//      against `proctex match PHOTO --db CATALOG` with the same defaults, runs alternated
//      (target <= 5%).
// Without --db it uses build/demo/catalog.sqlite (make demo builds it).
#include <sys/wait.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "server/server.h"

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

namespace {

double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[std::min(v.size() - 1, static_cast<size_t>(p * (v.size() - 1) + 0.5))];
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The server's Server-Timing of the last slider renders: "render" (device: the job's batch in
// flight + this render) per request, for the report.
std::vector<double> g_device_ms;

std::vector<double> slider_renders(httplib::Client& c, int n, int offset) {
  std::vector<double> ms;
  g_device_ms.clear();
  for (int i = 0; i < n; ++i) {
    const json body = {{"spec", {{"shader", "bricks"}, {"params", {{"rows", 4 + (i + offset) % 30}}}}}, {"size", 256}};
    const auto t = Clock::now();
    auto r = c.Post("/api/render", body.dump(), "application/json");
    if (!r || r->status != 200) throw std::runtime_error("render failed");
    ms.push_back(1000 * since(t));
    const std::string timing = r->get_header_value("Server-Timing");
    const auto at = timing.find("render;dur=");
    g_device_ms.push_back(at == std::string::npos ? -1 : std::stod(timing.substr(at + 11)));
  }
  return ms;
}

struct JobRun {
  std::string id;
  double first_preview = -1;  // seconds from the upload's start
  double first_preview_match = -1;  // the match's own elapsed time in that event (from its start)
  double total = 0;           // upload -> done event
  double match_seconds = 0;   // the library's own timings.total
};

// Uploads the photo and follows the job's events to the end.
JobRun run_job(int port, const std::string& photo, const json& options) {
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(600, 0);
  JobRun run;
  const auto t0 = Clock::now();
  httplib::MultipartFormDataItems items = {{"photo", photo, "p.png", "image/png"}, {"options", options.dump(), "", ""}};
  auto r = c.Post("/api/jobs/match", items);
  if (!r || r->status != 202) throw std::runtime_error("match upload failed: " + (r ? r->body : std::string("no answer")));
  run.id = json::parse(r->body)["id"];
  std::string buffer;
  c.Get("/api/jobs/" + run.id + "/events", [&](const char* d, size_t n) {
    buffer.append(d, n);
    for (size_t end; (end = buffer.find("\n\n")) != std::string::npos;) {
      const std::string block = buffer.substr(0, end);
      buffer.erase(0, end + 2);
      if (run.first_preview < 0 && block.find("\"preview\":") != std::string::npos) {
        run.first_preview = since(t0);
        const json j = json::parse(block.substr(block.find("data: ") + 6), nullptr, false);
        if (j.is_object() && j["progress"].contains("elapsed")) run.first_preview_match = j["progress"]["elapsed"];
      }
      if (block.rfind("event: done", 0) == 0) {
        run.total = since(t0);
        const json j = json::parse(block.substr(block.find("data: ") + 6));
        run.match_seconds = j["result"]["timings"]["total"];
      }
    }
    return true;
  });
  return run;
}

double cli_match(const std::string& db, const fs::path& photo, double* match_seconds) {
  const fs::path out = fs::temp_directory_path() / "proctex-bench-serve-cli.json";
  const std::string cmd = fmt::format("'{}' -q match '{}' --db '{}' -o '{}' >/dev/null", PROCTEX_BINARY, photo.string(), db, out.string());
  const auto t = Clock::now();
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("proctex match failed");
  const double s = since(t);
  *match_seconds = json::parse(slurp(out))["timings"]["total"];
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  std::string db = "build/demo/catalog.sqlite", markdown;
  fs::path photo = fs::path(PROCTEX_SOURCE_DIR) / "examples" / "brick.png";
  int renders = 30, runs = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i], v = argv[i + 1];
    if (a == "--db") db = v;
    else if (a == "--photo") photo = v;
    else if (a == "--renders") renders = std::stoi(v);
    else if (a == "--runs") runs = std::stoi(v);
    else if (a == "--markdown") markdown = v;
    else return std::fprintf(stderr, "usage: bench_serve [--db CATALOG] [--photo P] [--renders N] [--runs N] [--markdown FILE]\n"), 2;
  }
  if (!fs::exists(db)) return std::fprintf(stderr, "bench_serve: no catalogue at %s (run make demo, or pass --db)\n", db.c_str()), 1;
  const fs::path data = fs::temp_directory_path() / fmt::format("proctex-bench-serve-{}", getpid());
  const std::string bytes = slurp(photo);
  std::vector<JobRun> jobs;
  // Slider renders while a match job runs (the job started first, renders begin once it runs).
  auto busy_renders = [&](int port, httplib::Client& c, int offset) {
    JobRun background;
    std::thread job([&] { background = run_job(port, bytes, json::object()); });
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    auto ms = slider_renders(c, renders, offset);
    std::fprintf(stderr, "bench_serve: busy renders (end to end / device ms):");
    for (size_t i = 0; i < ms.size(); ++i) std::fprintf(stderr, " %.0f/%.0f", ms[i], g_device_ms[i]);
    std::fprintf(stderr, "\n");
    job.join();
    jobs.push_back(background);
    return ms;
  };
  proctex::server::ServerOptions o;
  o.port = 0;
  o.catalog = db;
  o.data = data;
  o.queue_limit = 16;
  // Without the UI-render priority first (a server of its own), for comparison.
  std::vector<double> busy_plain;
  {
    auto plain = o;
    plain.ui_render_priority = false;
    plain.data = data / "plain";
    auto server = std::make_unique<proctex::server::Server>(plain);
    const int port = server->bind();
    std::thread thread([&] { server->run(); });
    httplib::Client c("127.0.0.1", port);
    c.set_read_timeout(60, 0);
    slider_renders(c, 3, 100);
    busy_plain = busy_renders(port, c, 70);
    server->stop();
    thread.join();
  }
  auto server = std::make_unique<proctex::server::Server>(o);
  const int port = server->bind();
  std::thread thread([&] { server->run(); });
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(60, 0);

  slider_renders(c, 3, 100);  // warm-up: program build, caches
  const auto idle = slider_renders(c, renders, 0);
  const std::vector<double> busy = busy_renders(port, c, 50);
  // Service vs command line, alternated.
  std::vector<double> service_s, cli_s, service_match, cli_match_s;
  for (int i = 0; i < runs; ++i) {
    const JobRun r = run_job(port, bytes, json::object());
    jobs.push_back(r);
    service_s.push_back(r.total);
    service_match.push_back(r.match_seconds);
    double m = 0;
    cli_s.push_back(cli_match(db, photo, &m));
    cli_match_s.push_back(m);
  }
  std::vector<double> previews, preview_match;
  for (const auto& j : jobs) {
    previews.push_back(j.first_preview);
    preview_match.push_back(j.first_preview_match);
  }

  server->stop();
  thread.join();
  server.reset();
  std::error_code ec;
  fs::remove_all(data, ec);

  std::string md;
  md += fmt::format("| measure | median | p90 | max | target |\n|---|---|---|---|---|\n");
  md += fmt::format("| 256^2 slider render, idle (ms, n={}) | {:.0f} | {:.0f} | {:.0f} | < 150 |\n", idle.size(), percentile(idle, 0.5), percentile(idle, 0.9), percentile(idle, 1));
  md += fmt::format("| 256^2 slider render, match running (ms, n={}) | {:.0f} | {:.0f} | {:.0f} | < 150 |\n", busy.size(), percentile(busy, 0.5), percentile(busy, 0.9), percentile(busy, 1));
  md += fmt::format("| same, without the UI-render priority (ms, n={}) | {:.0f} | {:.0f} | {:.0f} | |\n", busy_plain.size(), percentile(busy_plain, 0.5), percentile(busy_plain, 0.9), percentile(busy_plain, 1));
  md += fmt::format("| first live preview after upload (s, n={}) | {:.2f} | {:.2f} | {:.2f} | < 2 |\n", previews.size(), percentile(previews, 0.5), percentile(previews, 0.9), percentile(previews, 1));
  md += fmt::format("| of which the match's own time to its first best (s) | {:.2f} | {:.2f} | {:.2f} | |\n", percentile(preview_match, 0.5), percentile(preview_match, 0.9), percentile(preview_match, 1));
  md += fmt::format("| match via the service, upload -> done (s, n={}) | {:.2f} | | {:.2f} | |\n", service_s.size(), percentile(service_s, 0.5), percentile(service_s, 1));
  md += fmt::format("| match via the CLI, process wall time (s, n={}) | {:.2f} | | {:.2f} | |\n", cli_s.size(), percentile(cli_s, 0.5), percentile(cli_s, 1));
  md += fmt::format("| service / CLI (median wall) | {:.3f} | | | <= 1.05 |\n", percentile(service_s, 0.5) / percentile(cli_s, 0.5));
  md += fmt::format("| search::match inside: service / CLI (median) | {:.3f} | | | |\n", percentile(service_match, 0.5) / percentile(cli_match_s, 0.5));
  std::printf("%s", md.c_str());
  if (!markdown.empty()) std::ofstream(markdown) << md;
  return 0;
}
