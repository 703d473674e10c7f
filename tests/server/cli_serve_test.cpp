// proctex serve as a user starts it: prints its URL (--port 0 picks a free port), serves, stops
// cleanly on SIGTERM; refuses a non-loopback address without --token.
#include <gtest/gtest.h>

#include <signal.h>
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
