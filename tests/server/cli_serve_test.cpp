// proctex serve as a user starts it: prints its URL (--port 0 picks a free port), serves, stops
// cleanly on SIGTERM; refuses a non-loopback address without --token.
#include <gtest/gtest.h>

#include <fstream>

#include <signal.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include "tests/server/support.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"
#include "tests/support/user_shader.h"

namespace proctex {
namespace {

using namespace proctex::testing;

// `proctex serve --port 0 --db DB --data DATA` as a child process, as a user starts it; `port` is
// read from the URL it prints first (0 if it printed none). `shader_path`: its $PROCTEX_SHADER_PATH.
struct ServeProcess {
  pid_t pid = -1;
  int out = -1;
  int port = 0;
  std::string line;

  ServeProcess(const std::string& db, const std::string& data, const std::string& shader_path = "") {
    int fds[2];
    if (pipe(fds) != 0) return;
    pid = fork();
    if (pid == 0) {
      dup2(fds[1], 1);
      close(fds[0]);
      if (!shader_path.empty()) setenv("PROCTEX_SHADER_PATH", shader_path.c_str(), 1);
      execl(PROCTEX_BINARY, PROCTEX_BINARY, "serve", "--port", "0", "--db", db.c_str(), "--data", data.c_str(), nullptr);
      _exit(127);
    }
    close(fds[1]);
    out = fds[0];
    char ch;
    while (read(out, &ch, 1) == 1 && ch != '\n') line += ch;
    const auto at = line.find("http://127.0.0.1:");
    if (at != std::string::npos) port = std::stoi(line.substr(at + 17));
  }
  // SIGTERM, then the exit status (waitpid's).
  int stop() {
    int status = 0;
    if (pid > 0) {
      kill(pid, SIGTERM);
      waitpid(pid, &status, 0);
      pid = -1;
    }
    if (out >= 0) close(out);
    out = -1;
    return status;
  }
  ~ServeProcess() { stop(); }
};

TEST(CliServe, PrintsItsUrlServesAndStopsOnSigterm) {
  TempDir dir;
  ServeProcess serve((dir / "none.sqlite").string(), (dir / "data").string());
  ASSERT_GT(serve.port, 0) << serve.line;
  const int port = serve.port;
  httplib::Client c("127.0.0.1", port);
  auto r = c.Get("/api/health");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_FALSE(body_json(r)["catalog_present"].get<bool>());
  const int status = serve.stop();
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(fs::exists(dir / "data" / "jobs.sqlite"));
}

TEST(CliServe, AMatchAgainstACatalogueOfAnEditedShaderIsRefused) {
  // The user edits a shader after building the catalogue: a match would search the old version's
  // samples. The service refuses it as the CLI does (409, a JSON error naming the shader and the
  // rebuild command) instead of starting a job.
  TempDir dir;
  const auto write_shader = [&](const char* gain) { testing::write_bands_shader(dir / "mine", gain); };
  write_shader("0.5");
  const std::string db = (dir / "cat.sqlite").string(), data = (dir / "data").string();
  const std::string env = "PROCTEX_SHADER_PATH='" + (dir / "mine").string() + "' ";
  ASSERT_EQ(std::system((env + "'" + PROCTEX_BINARY + "' catalog build --db '" + db +
                         "' --shaders checker,mine_bands --samples 6 --resolution 64 --probes 0 >/dev/null 2>&1")
                            .c_str()),
            0);
  write_shader("0.7");
  ServeProcess serve(db, data, (dir / "mine").string());
  ASSERT_GT(serve.port, 0) << serve.line;
  httplib::Client c("127.0.0.1", serve.port);
  const auto r = post_match(c, slurp(brick_photo()), nlohmann::json::object());
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 409) << r->body;
  const auto body = body_json(r);
  ASSERT_TRUE(body.is_object()) << r->body;
  const std::string error = body.dump();
  EXPECT_NE(error.find("stale"), std::string::npos) << error;
  EXPECT_NE(error.find("mine_bands"), std::string::npos) << error;
  EXPECT_NE(error.find("catalog build"), std::string::npos) << error;
  EXPECT_EQ(body_json(c.Get("/api/jobs"))["jobs"].size(), 0u) << "no job was started";
}

TEST(CliServe, NonLoopbackWithoutTokenIsAUsageError) {
  TempDir dir;
  const auto r = run_proctex("serve --bind 0.0.0.0 --port 0 --data '" + (dir / "data").string() + "'", dir.path());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(line_count(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("proctex: error: "), std::string::npos);
  EXPECT_NE(r.err.find("--token"), std::string::npos);
}

}  // namespace
}  // namespace proctex
