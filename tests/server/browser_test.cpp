// The web UI in a real browser: headless Debian chromium driven by puppeteer-core (pinned in
// tests/server/browser/package.json + package-lock.json, installed here with `npm ci` into
// build/browser-test the first time). The script uploads examples/brick.png on the match page,
// waits for the live preview to update and the result to appear, moves a slider twice and checks
// that the render changed, then renders a shader on the library page. Screenshots are kept in
// build/browser-test/screenshots/ as test artefacts.
#include <gtest/gtest.h>

#include <cstdlib>

#include "tests/server/support.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using namespace proctex::testing;

int sh(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(Browser, MatchPageShowsTheSearchLiveAndSlidersReRender) {
  ASSERT_EQ(sh("command -v node >/dev/null && command -v npm >/dev/null"), 0) << "node and npm: run scripts/install-deps.sh";
  const char* chromium = std::getenv("PROCTEX_CHROMIUM");
  const std::string browser = chromium && *chromium ? chromium : "/usr/bin/chromium";
  ASSERT_TRUE(fs::exists(browser)) << browser << ": run scripts/install-deps.sh (Debian package chromium)";

  const fs::path dir = build_dir() / "browser-test";
  const fs::path src = fs::path(PROCTEX_SOURCE_DIR) / "tests" / "server" / "browser";
  fs::create_directories(dir);
  for (const char* f : {"package.json", "package-lock.json", "match_flow.mjs"})
    fs::copy_file(src / f, dir / f, fs::copy_options::overwrite_existing);
  // npm ci again only when the lock file changed.
  const std::string lock = slurp(src / "package-lock.json");
  if (!fs::exists(dir / "node_modules" / "puppeteer-core") || slurp(dir / "node_modules" / ".proctex-lock") != lock) {
    ASSERT_EQ(sh("cd '" + dir.string() + "' && npm ci --no-audit --no-fund --loglevel=error >npm.log 2>&1"), 0)
        << "npm ci failed: see " << (dir / "npm.log");
    std::ofstream(dir / "node_modules" / ".proctex-lock") << lock;
  }

  TempDir data;
  server::ServerOptions o;
  o.port = 0;
  o.catalog = test_catalog();
  o.data = data / "data";
  RunningServer srv(o);
  const fs::path shots = dir / "screenshots";
  const std::string cmd = "cd '" + dir.string() + "' && node match_flow.mjs http://127.0.0.1:" + std::to_string(srv.port()) +
                          "/ '" + brick_photo().string() + "' '" + shots.string() + "' '" + browser + "' >browser.log 2>&1";
  const int code = sh(cmd);
  const std::string log = read_text(dir / "browser.log");
  std::printf("%s", log.c_str());
  EXPECT_EQ(code, 0) << log;
  EXPECT_TRUE(fs::exists(shots / "match-live.png"));
  EXPECT_TRUE(fs::exists(shots / "match-result.png"));
  EXPECT_TRUE(fs::exists(shots / "library.png"));
}

}  // namespace
}  // namespace proctex
