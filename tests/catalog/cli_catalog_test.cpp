// The catalogue from the command line: what a pipeline engineer types, including a killed build.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <fstream>
#include <map>
#include <thread>

#include <nlohmann/json.hpp>

#include "catalog/store.h"
#include "image/image.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"
#include "tests/support/user_shader.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;
using testing::run_proctex;

const char* kTiny = " --samples 10 --resolution 64 --probes 4 --set max_iterations=2 thumbnail=32 --seed 3";

class CatalogCli : public ::testing::Test {
 protected:
  testing::TempDir dir;
  testing::RunResult run(const std::string& args) { return run_proctex(args, dir.path()); }
  std::string path(const std::string& name) { return (dir / name).string(); }
  void expect_clean_error(const testing::RunResult& r, int code, const std::string& mentions) {
    EXPECT_EQ(r.exit_code, code) << r.err;
    EXPECT_EQ(r.err.rfind("proctex: error: ", 0), 0u) << r.err;
    EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << r.err;
  }
};

int64_t count_shaders(const std::string& db) {
  sqlite3* h = nullptr;
  int64_t n = -1;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_busy_timeout(h, 2000);
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(h, "SELECT count(*) FROM shaders", -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW)
      n = sqlite3_column_int64(s, 0);
    sqlite3_finalize(s);
  }
  sqlite3_close(h);
  return n;
}

TEST_F(CatalogCli, HelpOnEverySubcommand) {
  for (const char* cmd : {"catalog", "catalog build", "catalog merge", "catalog info", "catalog verify", "catalog sheet"}) {
    const auto r = run(std::string(cmd) + " --help");
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << cmd;
  }
}

TEST_F(CatalogCli, BuildShardMergeInfoVerifySheet) {
  const std::string shaders = " --shaders checker,circle,stripes";
  auto r = run("catalog build --db " + path("s1.sqlite") + shaders + kTiny + " --shard 1/2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["shard"], "1/2");
  EXPECT_EQ(j["shaders"].size(), 1u) << "balanced by cost: checker (8.1 s) alone, circle + stripes (5.9 s each)";
  EXPECT_EQ(j["plan"]["count"], 2);
  r = run("catalog build --db " + path("s2.sqlite") + shaders + kTiny + " --shard 2/2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run("catalog merge " + path("all.sqlite") + " " + path("s1.sqlite") + " " + path("s2.sqlite") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["added"].size(), 3u);

  r = run("catalog info --db " + path("all.sqlite") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["shaders"].size(), 3u);
  for (const auto& s : j["shaders"]) {
    EXPECT_GT(s["samples"].get<int>(), 1);
    EXPECT_FALSE(s["stale"].get<bool>());
    EXPECT_FALSE(s["coverage"].is_null());
  }
  r = run("catalog info --db " + path("all.sqlite"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("stripes"), std::string::npos);

  r = run("catalog verify --db " + path("all.sqlite") + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(nlohmann::json::parse(r.out)["ok"].get<bool>());

  r = run("catalog sheet stripes -o " + path("sheet.png") + " --db " + path("all.sqlite"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(load_image(path("sheet.png")).width, 64);

  // Rebuilding the same shard is incremental: everything skipped.
  r = run("catalog build --db " + path("s1.sqlite") + shaders + kTiny + " --shard 1/2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto rebuilt = nlohmann::json::parse(r.out);
  for (const auto& s : rebuilt["shaders"]) EXPECT_EQ(s["status"], "skipped");
}

TEST_F(CatalogCli, DefaultLocationFromEnvironment) {
  const auto r = run_proctex("catalog info", dir.path());  // PROCTEX_CATALOG unset here: may not exist
  (void)r;
  const std::string env = "PROCTEX_CATALOG=" + path("env.sqlite") + " ";
  const std::string bin = std::string("'") + PROCTEX_BINARY + "'";
  const int rc = std::system((env + bin + " -q catalog build --shaders checker" + kTiny + " >/dev/null 2>&1").c_str());
  EXPECT_EQ(rc, 0);
  EXPECT_TRUE(fs::exists(path("env.sqlite")));
}

TEST_F(CatalogCli, BadInputGivesOneLineErrors) {
  expect_clean_error(run("catalog build --db " + path("x.sqlite") + " --shaders nosuchshader"), 2, "nosuchshader");
  expect_clean_error(run("catalog build --db " + path("x.sqlite") + " --shard 3/2"), 2, "shard");
  expect_clean_error(run("catalog build --db " + path("x.sqlite") + " --set bogus=1"), 2, "bogus");
  expect_clean_error(run("catalog info --db " + path("missing.sqlite")), 1, "no catalogue");
  {
    std::ofstream(path("junk.sqlite")) << std::string(5000, 'j');
  }
  expect_clean_error(run("catalog build --shaders checker --db " + path("junk.sqlite") + kTiny), 1, "junk.sqlite");
  expect_clean_error(run("catalog verify --db " + path("junk.sqlite")), 1, "junk.sqlite");
  {
    std::ofstream(path("file")) << "x";
  }
  expect_clean_error(run("catalog build --shaders checker --db " + path("file") + "/c.sqlite" + kTiny), 1, "c.sqlite");
}

// A build killed with SIGKILL mid-way leaves a healthy file holding only complete shaders; rerunning
// finishes the job.
TEST_F(CatalogCli, KilledBuildIsSafeAndResumable) {
  const std::string db = path("kill.sqlite");
  const std::string shaders = "checker,circle,stripes,star,rectangle,superellipse";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    dup2(devnull, 2);
    execl(PROCTEX_BINARY, PROCTEX_BINARY, "-q", "catalog", "build", "--db", db.c_str(), "--shaders", shaders.c_str(),
          "--samples", "16", "--resolution", "128", "--probes", "4", "--seed", "3", static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait until at least one shader is committed, then kill without warning.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(150);
  while (count_shaders(db) < 1 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  std::this_thread::sleep_for(std::chrono::milliseconds(150));  // likely inside the next shader
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  const int64_t done = count_shaders(db);
  ASSERT_GE(done, 1);
  if (WIFEXITED(status)) std::fprintf(stderr, "note: the build finished before the kill\n");

  auto r = run("catalog verify --db " + db + " --samples 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err << r.out;
  auto v = nlohmann::json::parse(r.out);
  EXPECT_TRUE(v["ok"].get<bool>());
  EXPECT_EQ(v["shaders"].size(), static_cast<size_t>(done)) << "only complete shaders are visible";

  r = run("catalog build --db " + db + " --shaders " + shaders +
          " --samples 16 --resolution 128 --probes 4 --seed 3 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  int skipped = 0;
  const auto resumed = nlohmann::json::parse(r.out);
  for (const auto& s : resumed["shaders"]) skipped += s["status"] == "skipped";
  EXPECT_EQ(skipped, done) << "completed shaders are kept, the rest is built";
  EXPECT_EQ(count_shaders(db), 6);
  r = run("catalog verify --db " + db + " --samples 1");
  EXPECT_EQ(r.exit_code, 0) << r.err << r.out;
}

TEST_F(CatalogCli, NewerSchemaRefusedByEveryCommand) {
  auto r = run("catalog build --db " + path("c.sqlite") + " --shaders checker" + kTiny);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  {
    sqlite3* h = nullptr;
    sqlite3_open(path("c.sqlite").c_str(), &h);
    // One version beyond what this proctex supports (the schema grows; the test must not pin a number).
    const std::string newer = "PRAGMA user_version = " + std::to_string(catalog::kSchemaVersion + 1) +
                              "; PRAGMA wal_checkpoint(TRUNCATE);";
    sqlite3_exec(h, newer.c_str(), nullptr, nullptr, nullptr);
    sqlite3_close(h);
  }
  expect_clean_error(run("catalog build --db " + path("c.sqlite") + " --shaders checker" + kTiny), 1, "newer");
  expect_clean_error(run("catalog info --db " + path("c.sqlite")), 1, "newer");
  expect_clean_error(run("catalog verify --db " + path("c.sqlite")), 1, "newer");
}

// A shader edited after the build: `catalog build` rebuilds it alone, and until then `match` refuses
// the catalogue instead of mixing the old version's samples with the new shader (issue 12).
TEST_F(CatalogCli, EditedShaderIsRebuiltAloneAndMatchRefusesTheStaleCatalogue) {
  const auto write_shader = [&](const char* gain) { testing::write_bands_shader(dir / "mine", gain); };
  write_shader("0.5");
  const std::string env = "PROCTEX_SHADER_PATH='" + (dir / "mine").string() + "' ";
  const std::string bin = env + "'" + PROCTEX_BINARY + "'";
  const std::string build = bin + " catalog build --db " + path("cat.sqlite") + " --shaders checker,mine_bands" + kTiny;
  ASSERT_EQ(std::system((build + " >/dev/null 2>&1").c_str()), 0);
  ASSERT_EQ(run("render checker -o " + path("photo.png") + " --size 64").exit_code, 0);

  write_shader("0.7");  // the user edits the shader
  const int rc = std::system((bin + " match " + path("photo.png") + " --db " + path("cat.sqlite") + " >" +
                              path("out.txt") + " 2>" + path("err.txt")).c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 1);
  const std::string err = testing::read_text(path("err.txt"));
  EXPECT_EQ(err.rfind("proctex: error: ", 0), 0u) << err;
  EXPECT_EQ(testing::line_count(err), 1) << err;
  EXPECT_NE(err.find("stale"), std::string::npos) << err;
  EXPECT_NE(err.find("mine_bands"), std::string::npos) << err;
  EXPECT_EQ(err.find("checker"), std::string::npos) << err;  // unchanged shaders are not blamed

  // The command the error suggests, as the user would paste it: it rebuilds the edited shader
  // alone, with the catalogue's own settings (not the defaults: 48 samples at 256 px, seed 1).
  const std::string hint = err.substr(std::min(err.find("proctex catalog build"), err.size()));
  ASSERT_FALSE(hint.empty()) << err;
  const std::string suggested = bin + hint.substr(std::string("proctex").size(), hint.find_last_not_of("\n)") - 6);
  ASSERT_EQ(std::system((suggested + " --json >" + path("build.json") + " 2>/dev/null").c_str()), 0) << suggested;
  const auto report = nlohmann::json::parse(testing::read_text(path("build.json")));
  std::map<std::string, std::string> status;
  for (const auto& s : report["shaders"]) status[s["shader"]] = s["status"];
  EXPECT_EQ(status["mine_bands"], "rebuilt") << report.dump();
  EXPECT_EQ(report["shaders"].size(), 1u) << report.dump();  // no library shader added
  const int info = std::system((bin + " catalog info --db " + path("cat.sqlite") + " --json >" + path("info.json") +
                                " 2>/dev/null").c_str());
  ASSERT_EQ(WEXITSTATUS(info), 0);
  const auto shaders = nlohmann::json::parse(testing::read_text(path("info.json")))["shaders"];
  ASSERT_EQ(shaders.size(), 2u) << shaders.dump();
  for (const auto& s : shaders) {
    EXPECT_FALSE(s["stale"].get<bool>()) << s.dump();
    EXPECT_EQ(s["resolution"], 64) << s.dump();
    EXPECT_EQ(s["seed"], 3) << s.dump();
  }
  // A second refresh changes nothing; an option given explicitly does.
  ASSERT_EQ(std::system((build + " --json >" + path("again.json") + " 2>/dev/null").c_str()), 0);
  for (const auto& s : nlohmann::json::parse(testing::read_text(path("again.json")))["shaders"])
    EXPECT_EQ(s["status"], "skipped") << s.dump();
  ASSERT_EQ(std::system((bin + " catalog build --db " + path("cat.sqlite") + " --shaders checker --seed 4 --json >" +
                         path("seed.json") + " 2>/dev/null").c_str()), 0);
  const auto reseeded = nlohmann::json::parse(testing::read_text(path("seed.json")));
  EXPECT_EQ(reseeded["shaders"][0]["reason"], "settings or seed changed") << reseeded.dump();
}

}  // namespace
}  // namespace proctex
