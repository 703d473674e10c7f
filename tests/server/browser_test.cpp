// The web UI in a real browser: headless Debian chromium driven by puppeteer-core (pinned in
// tests/server/browser/package.json + package-lock.json, installed here with `npm ci` into
// build/browser-test the first time). The script uploads examples/brick.png on the match page,
// waits for the live preview to update and the result to appear, moves a slider twice and checks
// that the render changed, then renders a shader on the library page; on the synth page it drops
// an exemplar and sees the result, its 2x2 tiling and a new seed (synth_flow.mjs). Screenshots are
// kept in build/browser-test/screenshots/ as test artefacts.
#include <gtest/gtest.h>

#include <sys/file.h>
#include <fcntl.h>
#include <unistd.h>

#include <cstdlib>

#include "image/image.h"
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

// The browser, and build/browser-test with the scripts and puppeteer-core installed (npm ci again
// only when the lock file changed). Empty on failure (the test has failed already).
std::string prepare_browser_test(fs::path& dir) {
  EXPECT_EQ(sh("command -v node >/dev/null && command -v npm >/dev/null"), 0) << "node and npm: run scripts/install-deps.sh";
  const char* chromium = std::getenv("PROCTEX_CHROMIUM");
  const std::string browser = chromium && *chromium ? chromium : "/usr/bin/chromium";
  EXPECT_TRUE(fs::exists(browser)) << browser << ": run scripts/install-deps.sh (Debian package chromium)";
  if (!fs::exists(browser)) return "";
  dir = build_dir() / "browser-test";
  const fs::path src = fs::path(PROCTEX_SOURCE_DIR) / "tests" / "server" / "browser";
  // One npm ci at a time (ctest may run the browser tests in parallel).
  fs::create_directories(dir);
  const int fd = ::open((dir / ".lock").c_str(), O_CREAT | O_RDWR, 0644);
  ::flock(fd, LOCK_EX);
  for (const char* f : {"package.json", "package-lock.json", "match_flow.mjs", "synth_flow.mjs"})
    fs::copy_file(src / f, dir / f, fs::copy_options::overwrite_existing);
  const std::string lock = slurp(src / "package-lock.json");
  bool ok = true;
  if (!fs::exists(dir / "node_modules" / "puppeteer-core") || slurp(dir / "node_modules" / ".proctex-lock") != lock) {
    ok = sh("cd '" + dir.string() + "' && npm ci --no-audit --no-fund --loglevel=error >npm.log 2>&1") == 0;
    EXPECT_TRUE(ok) << "npm ci failed: see " << (dir / "npm.log");
    if (ok) std::ofstream(dir / "node_modules" / ".proctex-lock") << lock;
  }
  ::flock(fd, LOCK_UN);
  ::close(fd);
  return ok ? browser : "";
}

TEST(Browser, MatchPageShowsTheSearchLiveAndSlidersReRender) {
  fs::path dir;
  const std::string browser = prepare_browser_test(dir);
  ASSERT_FALSE(browser.empty());

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

namespace proctex {
namespace {

using namespace proctex::testing;

TEST(Browser, SynthPageTakesADroppedExemplarAndShowsTheResultAndItsTiling) {
  fs::path dir;
  const std::string browser = prepare_browser_test(dir);
  ASSERT_FALSE(browser.empty());
  TempDir data;
  // A 128 px exemplar: the brick photo's top-left quarter, scaled down.
  const fs::path exemplar = data / "bricks-128.png";
  const Image photo = load_image(brick_photo());
  save_image(resize(crop(photo, 0, 0, 256, 256), 128, 128), exemplar);
  server::ServerOptions o;
  o.port = 0;
  o.catalog = data / "no-catalogue.sqlite";  // synthesis needs none
  o.data = data / "data";
  RunningServer srv(o);
  const fs::path shots = dir / "screenshots";
  const std::string cmd = "cd '" + dir.string() + "' && node synth_flow.mjs http://127.0.0.1:" + std::to_string(srv.port()) +
                          "/ '" + exemplar.string() + "' '" + shots.string() + "' '" + browser + "' >synth-browser.log 2>&1";
  const int code = sh(cmd);
  const std::string log = read_text(dir / "synth-browser.log");
  std::printf("%s", log.c_str());
  EXPECT_EQ(code, 0) << log;
  EXPECT_TRUE(fs::exists(shots / "synth-result.png"));
  EXPECT_TRUE(fs::exists(shots / "synth-tiled.png"));
}

}  // namespace
}  // namespace proctex
