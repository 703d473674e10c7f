#pragma once
// Helpers of the server tests: a small catalogue shared by every test process (built once, under
// the build folder, with a file lock since ctest runs tests in parallel), and a real server on
// loopback (port 0) run on a thread of the test.
#include <sys/file.h>
#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "catalog/catalog.h"
#include "server/server.h"

namespace proctex::testing {

namespace fs = std::filesystem;

inline fs::path build_dir() { return fs::path(PROCTEX_BINARY).parent_path().parent_path(); }
inline fs::path brick_photo() { return fs::path(PROCTEX_SOURCE_DIR) / "examples" / "brick.png"; }

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// bricks, stripes and clouds, 6 samples each at the match's resolution: enough for a match to
// find bricks in the brick photo in a few seconds. Incremental: a second build takes ~1 s.
inline fs::path test_catalog() {
  const fs::path dir = build_dir() / "server-test-cache";
  fs::create_directories(dir);
  const fs::path db = dir / "catalog.sqlite";
  const int fd = ::open((dir / "lock").c_str(), O_CREAT | O_RDWR, 0644);
  ::flock(fd, LOCK_EX);
  catalog::BuildOptions o;
  o.db = db;
  o.shaders = {"bricks", "stripes", "clouds"};
  o.settings.samples = 6;
  o.settings.probes = 0;
  o.settings.max_iterations = 1;
  o.seed = 5;
  o.jobs = 2;
  catalog::build(o);
  ::flock(fd, LOCK_UN);
  ::close(fd);
  return db;
}

class RunningServer {
 public:
  explicit RunningServer(server::ServerOptions o) : server_(std::make_unique<server::Server>(std::move(o))) {
    port_ = server_->bind();
    thread_ = std::thread([this] { server_->run(); });
  }
  ~RunningServer() { shutdown(); }
  // Stops serving and destroys the server (jobs still running are left "interrupted").
  void shutdown() {
    if (!server_) return;
    server_->stop();
    thread_.join();
    server_.reset();
  }
  int port() const { return port_; }
  httplib::Client client(int timeout_seconds = 60) const {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(timeout_seconds, 0);
    c.set_connection_timeout(30, 0);
    return c;
  }

 private:
  std::unique_ptr<server::Server> server_;
  std::thread thread_;
  int port_ = 0;
};

inline nlohmann::json body_json(const httplib::Result& r) {
  if (!r) return nullptr;
  return nlohmann::json::parse(r->body, nullptr, false);
}

// Uploads a photo as a match job (multipart: photo + options JSON).
inline httplib::Result post_match(httplib::Client& c, const std::string& bytes, const nlohmann::json& options) {
  httplib::MultipartFormDataItems items = {{"photo", bytes, "my photo.png", "image/png"},
                                           {"options", options.dump(), "", "application/json"}};
  return c.Post("/api/jobs/match", items);
}

// Polls GET /api/jobs/ID until `pred(status)` or the timeout; returns the last status.
template <typename Pred>
nlohmann::json wait_for(httplib::Client& c, const std::string& id, Pred pred, double seconds = 60) {
  nlohmann::json status;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1000));
  while (std::chrono::steady_clock::now() < end) {
    status = body_json(c.Get("/api/jobs/" + id));
    if (status.is_object() && pred(status)) return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return status;
}

inline bool finished(const nlohmann::json& s) {
  const std::string st = s.value("state", "");
  return st == "done" || st == "cancelled" || st == "failed" || st == "interrupted";
}

}  // namespace proctex::testing
