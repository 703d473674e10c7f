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

namespace proctex {
namespace {

using namespace proctex::testing;

TEST(CliServe, PrintsItsUrlServesAndStopsOnSigterm) {
  TempDir dir;
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const std::string db = (dir / "none.sqlite").string(), data = (dir / "data").string();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], 1);
    close(out[0]);
    execl(PROCTEX_BINARY, PROCTEX_BINARY, "serve", "--port", "0", "--db", db.c_str(), "--data", data.c_str(), nullptr);
    _exit(127);
  }
  close(out[1]);
  std::string line;
  char ch;
  while (read(out[0], &ch, 1) == 1 && ch != '\n') line += ch;
  const auto at = line.find("http://127.0.0.1:");
  ASSERT_NE(at, std::string::npos) << line;
  const int port = std::stoi(line.substr(at + 17));
  EXPECT_GT(port, 0);
  httplib::Client c("127.0.0.1", port);
  auto r = c.Get("/api/health");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_FALSE(body_json(r)["catalog_present"].get<bool>());
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  close(out[0]);
  EXPECT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_TRUE(fs::exists(dir / "data" / "jobs.sqlite"));
}

TEST(CliServe, AMatchAgainstACatalogueOfAnEditedShaderIsRefused) {
  // The user edits a shader after building the catalogue: a match would search the old version's
  // samples. The service refuses it as the CLI does (409, a JSON error naming the shader and the
  // rebuild command) instead of starting a job.
  TempDir dir;
  fs::create_directories(dir / "mine");
  const auto write_shader = [&](const char* gain) {
    std::ofstream(dir / "mine" / "mine_bands.cl")
        << "// @shader \"bands for a test\"\n// @param float size = 0.5 [0.1, 1] \"band size\"\n"
           "float3 shade(float2 p, float fw, uint seed, const Params P) {\n"
           "  return (float3)(" << gain << "f * pt_fract(p.x * 4.0f / P.size));\n}\n";
  };
  write_shader("0.5");
  const std::string db = (dir / "cat.sqlite").string(), data = (dir / "data").string();
  const std::string env = "PROCTEX_SHADER_PATH='" + (dir / "mine").string() + "' ";
  ASSERT_EQ(std::system((env + "'" + PROCTEX_BINARY + "' catalog build --db '" + db +
                         "' --shaders checker,mine_bands --samples 6 --resolution 64 --probes 0 >/dev/null 2>&1")
                            .c_str()),
            0);
  write_shader("0.7");
  int out[2];
  ASSERT_EQ(pipe(out), 0);
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], 1);
    close(out[0]);
    setenv("PROCTEX_SHADER_PATH", (dir / "mine").c_str(), 1);
    execl(PROCTEX_BINARY, PROCTEX_BINARY, "-q", "serve", "--port", "0", "--db", db.c_str(), "--data", data.c_str(),
          nullptr);
    _exit(127);
  }
  close(out[1]);
  std::string line;
  char ch;
  while (read(out[0], &ch, 1) == 1 && ch != '\n') line += ch;
  const auto at = line.find("http://127.0.0.1:");
  ASSERT_NE(at, std::string::npos) << line;
  httplib::Client c("127.0.0.1", std::stoi(line.substr(at + 17)));
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
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  close(out[0]);
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
