// proctex match over a folder / list of photos: per-photo results, the index, resuming, shards, a
// bad photo in the middle. Real catalogue (3 cheap shaders), real renders as photos.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;
using testing::run_proctex;
using testing::TempDir;

const char* kQuick = " --starts 1 --race 2 --evaluations 20 --candidates 3";

class MatchBatch : public ::testing::Test {
 protected:
  // ctest runs each test in its own process: the catalogue lives in the build tree and is built
  // incrementally under a lock (the first process builds it, the others find it unchanged).
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const std::string lock = db() + ".lock";
    const int fd = ::open(lock.c_str(), O_CREAT | O_RDWR, 0644);
    ASSERT_GE(fd, 0);
    ::flock(fd, LOCK_EX);
    const auto r = run_proctex("-q catalog build --db '" + db() + "' --shaders checker,stripes,circle --samples 12 "
                               "--probes 0 --set max_iterations=1 --seed 2",
                               dir_->path());
    ::flock(fd, LOCK_UN);
    ::close(fd);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string db() {
    return (fs::path(PROCTEX_BINARY).parent_path().parent_path() / "tests" / "match-batch-catalog.sqlite").string();
  }

  TempDir dir;
  fs::path photos() const { return dir / "photos"; }
  void make_photos() {
    fs::create_directories(photos() / "sub");
    for (const auto& [name, spec] : std::vector<std::pair<std::string, std::string>>{
             {"a-checker.png", "checker:seed=9001"}, {"sub/c-circle.png", "circle:seed=9003"}}) {
      const auto r = run_proctex("-q render '" + spec + "' --size 128 -o '" + (photos() / name).string() + "'", dir.path());
      ASSERT_EQ(r.exit_code, 0) << r.err;
    }
    std::ofstream(photos() / "b-broken.jpg") << "this is not a JPEG";
    std::ofstream(photos() / "notes.txt") << "not a photo, not listed";
  }
  testing::RunResult batch(const std::string& input, const std::string& extra = "") {
    return run_proctex("match '" + input + "' --db '" + db() + "' --out-dir '" + (dir / "out").string() + "'" + kQuick + extra,
                       dir.path());
  }
  nlohmann::json index(const std::string& stem = "index") const {
    return nlohmann::json::parse(testing::read_text(dir / "out" / (stem + ".json")));
  }
  static TempDir* dir_;
};
TempDir* MatchBatch::dir_ = nullptr;

TEST_F(MatchBatch, FolderResultsIndexBadPhotoAndResume) {
  make_photos();
  auto r = batch(photos().string());
  // The broken photo does not stop the batch; the command says so at the end, in one line.
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("proctex: error: 1 of 3 photos failed"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("b-broken.jpg"), std::string::npos) << r.err;
  const auto j = index();
  ASSERT_EQ(j["photos"].size(), 3u) << j.dump();
  std::map<std::string, nlohmann::json> rows;
  for (const auto& p : j["photos"]) rows[p["photo"].get<std::string>()] = p;
  ASSERT_TRUE(rows.count("a-checker.png") && rows.count("b-broken.jpg") && rows.count("sub/c-circle.png")) << j.dump();
  EXPECT_EQ(rows["b-broken.jpg"]["status"], "error");
  EXPECT_FALSE(rows["b-broken.jpg"]["error"].get<std::string>().empty());
  // A render of a catalogued shader is recovered (the user's first sanity check of a batch).
  EXPECT_EQ(rows["a-checker.png"]["shader"], "checker") << rows["a-checker.png"].dump();
  EXPECT_EQ(rows["sub/c-circle.png"]["shader"], "circle") << rows["sub/c-circle.png"].dump();
  for (const char* name : {"a-checker.png", "sub/c-circle.png"}) {
    EXPECT_EQ(rows[name]["status"], "matched");
    const double s = rows[name]["similarity"];
    EXPECT_GT(s, 0.0);
    EXPECT_LE(s, 1.0);
    // A render of a catalogued shader is expressed ("good" needs more than S: the verdict rules are
    // tested in tests/search/match_test.cpp; the index repeats the result's verdict, below).
    EXPECT_TRUE(rows[name]["verdict"] == "good" || rows[name]["verdict"] == "approximate") << rows[name].dump();
  }
  // One result JSON per photo, with the full match (spec, similarity, verdict) and what keys it.
  const auto res = nlohmann::json::parse(testing::read_text(dir / "out" / "sub__c-circle.png.json"));
  EXPECT_EQ(res["status"], "ok");
  EXPECT_EQ(res["match"]["spec"]["shader"], "circle");
  EXPECT_DOUBLE_EQ(res["match"]["similarity"].get<double>(), rows["sub/c-circle.png"]["similarity"].get<double>());
  EXPECT_EQ(res["match"]["verdict"], rows["sub/c-circle.png"]["verdict"]);
  for (const char* key : {"photo_hash", "options_hash", "catalogue_hash"}) EXPECT_TRUE(res.contains(key)) << key;
  // The CSV index: a header and one row per photo.
  const std::string csv = testing::read_text(dir / "out" / "index.csv");
  EXPECT_EQ(csv.rfind("photo,shader,similarity,verdict,status", 0), 0u) << csv;
  EXPECT_EQ(testing::line_count(csv), 4) << csv;
  EXPECT_NE(csv.find("a-checker.png,checker,"), std::string::npos) << csv;

  // Resume: nothing changed, nothing is matched again (result files untouched).
  const auto before = fs::last_write_time(dir / "out" / "a-checker.png.json");
  r = batch(photos().string());
  EXPECT_EQ(r.exit_code, 1);
  const auto again = index();
  for (const auto& p : again["photos"]) EXPECT_EQ(p["status"], p["photo"] == "b-broken.jpg" ? "error" : "cached") << p.dump();
  EXPECT_EQ(fs::last_write_time(dir / "out" / "a-checker.png.json"), before);
  // A changed photo is matched again; the others stay; other options redo everything.
  fs::copy_file(photos() / "a-checker.png", photos() / "sub" / "c-circle.png", fs::copy_options::overwrite_existing);
  r = batch(photos().string());
  rows.clear();
  const auto changed = index();
  for (const auto& p : changed["photos"]) rows[p["photo"].get<std::string>()] = p;
  ASSERT_EQ(rows.size(), 3u) << r.err << changed.dump();
  EXPECT_EQ(rows["sub/c-circle.png"]["status"], "matched");
  EXPECT_EQ(rows["sub/c-circle.png"]["shader"], "checker") << "the photo is a checker now";
  EXPECT_EQ(rows["a-checker.png"]["status"], "cached");
  r = batch(photos().string(), " --screen 3");
  const auto other = index();
  for (const auto& p : other["photos"]) EXPECT_NE(p["status"], "cached") << p.dump();
}

TEST_F(MatchBatch, ShardsOfAListCoverEveryPhotoOnce) {
  make_photos();
  {
    std::ofstream list(dir / "list.txt");
    list << "# photos to match\nphotos/a-checker.png\n\nphotos/sub/c-circle.png\nphotos/missing.png\n";
  }
  std::multiset<std::string> seen;
  for (int i = 1; i <= 2; ++i) {
    const auto r = batch((dir / "list.txt").string(), " --shard " + std::to_string(i) + "/2");
    const auto j = index("index-" + std::to_string(i) + "-of-2");
    for (const auto& p : j["photos"]) seen.insert(p["photo"]);
    EXPECT_EQ(j["shard"], std::to_string(i) + "/2");
    (void)r;
  }
  EXPECT_EQ(seen, (std::multiset<std::string>{"photos/a-checker.png", "photos/missing.png", "photos/sub/c-circle.png"}));
  // The full pass after the shards reuses every result: the complete index without new searches.
  const auto r = batch((dir / "list.txt").string(), " --json");
  const auto summary = nlohmann::json::parse(r.out);
  EXPECT_EQ(summary["matched"], 0) << r.out;
  EXPECT_EQ(summary["cached"], 2) << r.out;
  EXPECT_EQ(summary["failed"], 1) << "missing.png (no result is current for a file that is not there): " << r.out;
}

TEST_F(MatchBatch, BadBatchInputsAreOneLineErrors) {
  fs::create_directories(dir / "empty");
  auto r = batch((dir / "empty").string());
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err.rfind("proctex: error: no photos in", 0), 0u) << r.err;
  r = batch((dir / "nope").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(testing::line_count(r.err), 1) << r.err;
  make_photos();
  r = batch(photos().string(), " --shard 3/2");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--shard"), std::string::npos) << r.err;
  r = batch(photos().string(), " --render '" + (dir / "r.png").string() + "'");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--render is for one photo"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "out" / "index.csv"));
}

}  // namespace
}  // namespace proctex
