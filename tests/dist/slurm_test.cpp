// Catalogue builds and batch matching on a real Slurm cluster: munged + slurmctld + slurmd on this
// machine (scripts/slurm/local-cluster.sh: config, keys, state and logs in a temp folder, started
// and stopped here, no system service). The test submits the same job scripts a user submits.
// Skipped, with the reason, only when the daemons cannot start (Slurm or munge not installed).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <fstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "catalog/catalog.h"
#include "catalog/store.h"
#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

const std::string kScripts = std::string(PROCTEX_SOURCE_DIR) + "/scripts";
// 6 cheap shaders, 3 shards of 2 (balanced by the committed cost table), small settings.
const std::string kBuildArgs =
    "--shaders checker,circle,stripes,grid,swirl,rectangle --samples 8 --probes 2 "
    "--set max_iterations=1 --seed 3";

struct Shell {
  int code = -1;
  std::string out, err;
};
Shell sh(const std::string& cmd, const fs::path& scratch) {
  const auto o = scratch / "sh.out", e = scratch / "sh.err";
  const int status = std::system((cmd + " >'" + o.string() + "' 2>'" + e.string() + "' </dev/null").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, testing::read_text(o), testing::read_text(e)};
}

void write_exec(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
  fs::permissions(p, fs::perms::owner_all);
}

// The cluster for one test; stopped (exactly its daemons, by their pid files) on destruction.
class Cluster {
 public:
  explicit Cluster(const fs::path& dir) : dir_(dir) {
    const Shell r = sh("'" + kScripts + "/slurm/local-cluster.sh' start '" + dir.string() + "'", dir.parent_path());
    started_ = r.code == 0;
    reason_ = r.err;
    env_ = "SLURM_CONF='" + (dir / "slurm.conf").string() + "' POCL_CACHE_DIR='" +
           (fs::path(PROCTEX_BINARY).parent_path().parent_path() / "pocl-cache").string() + "' ";
  }
  ~Cluster() { sh("'" + kScripts + "/slurm/local-cluster.sh' stop '" + dir_.string() + "'", dir_.parent_path()); }
  bool started() const { return started_; }
  const std::string& reason() const { return reason_; }
  const std::string& env() const { return env_; }
  // Waits until none of the jobs is queued or running; false on timeout.
  bool wait(const std::string& jobs, double seconds, const fs::path& scratch) const {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
      const Shell q = sh(env_ + "squeue -h -j " + jobs, scratch);
      if (q.code == 0 && q.out.find_first_not_of(" \n") == std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
    }
    return false;
  }

 private:
  fs::path dir_;
  bool started_ = false;
  std::string reason_, env_;
};

std::vector<std::string> split_ws(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string w; in >> w;) out.push_back(w);
  return out;
}

TEST(Slurm, ShardArrayMergesToTheSingleProcessBuildAndAKilledTaskIsRequeued) {
  const auto t0 = std::chrono::steady_clock::now();
  TempDir dir;
  Cluster cluster(dir / "cluster");
  if (!cluster.started()) GTEST_SKIP() << "cannot start a local Slurm cluster: " << cluster.reason();

  // The first run of shard 2 is killed (SIGKILL, by this test) once it has saved its first shader:
  // the wrapper only records the real process's pid.
  const fs::path run = dir / "run";
  write_exec(dir / "proctex",
             "#!/usr/bin/env bash\n"
             "if [[ \"$*\" == *'--shard 2/3'* && ! -e '" + (dir / "killed-once").string() + "' ]]; then\n"
             "  touch '" + (dir / "killed-once").string() + "'\n"
             "  '" PROCTEX_BINARY "' \"$@\" & echo $! > '" + (dir / "victim.pid").string() + "'\n"
             "  wait $!; exit $?\n"
             "fi\n"
             "exec '" PROCTEX_BINARY "' \"$@\"\n");
  const Shell sub = sh(cluster.env() + "'" + kScripts + "/slurm/submit-catalog.sh' --shards 3 --cpus 1 --out '" +
                           run.string() + "' --proctex '" + (dir / "proctex").string() + "' -- " + kBuildArgs,
                       dir.path());
  ASSERT_EQ(sub.code, 0) << sub.err;
  const auto ids = split_ws(sub.out);
  ASSERT_EQ(ids.size(), 2u) << sub.out;

  // Kill shard 2 after its first shader is committed (a real mid-build kill of a Slurm task).
  const fs::path shard2 = run / "shard-2-of-3.sqlite";
  bool killed = false;
  for (int i = 0; i < 3000 && !killed; ++i) {  // up to 60 s
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (!fs::exists(dir / "victim.pid") || !fs::exists(shard2)) continue;
    try {
      catalog::Store s(shard2, catalog::Store::Access::Read);
      if (s.shaders().empty()) continue;
    } catch (const std::exception&) {
      continue;  // still being created
    }
    const pid_t pid = std::stoi(testing::read_text(dir / "victim.pid"));
    ASSERT_EQ(kill(pid, SIGKILL), 0) << "shard 2 finished before it could be killed";
    killed = true;
  }
  ASSERT_TRUE(killed) << "shard 2 never saved a shader";
  ASSERT_TRUE(cluster.wait(ids[0] + "," + ids[1], 150, dir.path())) << "jobs still queued after 150 s";
  const std::string log2 = testing::read_text(run / "logs" / "shard-2.log");
  EXPECT_NE(log2.find("requeueing shard 2/3"), std::string::npos) << log2;
  EXPECT_NE(log2.find("restart 1"), std::string::npos) << "the requeued task ran again: " << log2;
  EXPECT_NE(log2.find("shard 2/3 done"), std::string::npos) << log2;
  // The rerun kept the shader saved before the kill and built the rest.
  const auto report = nlohmann::json::parse(testing::read_text(run / "shard-2-of-3.json"));
  int kept = 0;
  for (const auto& s : report["shaders"]) kept += s["status"] == "skipped";
  EXPECT_GE(kept, 1) << report.dump();

  ASSERT_TRUE(fs::exists(run / "catalog.sqlite")) << testing::read_text(run / "logs" / "merge.log");
  const auto verify = nlohmann::json::parse(testing::read_text(run / "verify.json"));
  EXPECT_TRUE(verify["ok"].get<bool>()) << verify.dump();

  // A single-process build of the same settings: the same samples, features, graphs, thumbnails.
  const auto single = testing::run_proctex("-q catalog build --db '" + (dir / "single.sqlite").string() + "' " + kBuildArgs,
                                           dir.path());
  ASSERT_EQ(single.exit_code, 0) << single.err;
  catalog::Store a(dir / "single.sqlite", catalog::Store::Access::Read), b(run / "catalog.sqlite", catalog::Store::Access::Read);
  const auto sa = a.shaders(), sb = b.shaders();
  ASSERT_EQ(sa.size(), 6u);
  ASSERT_EQ(sb.size(), sa.size());
  for (size_t k = 0; k < sa.size(); ++k) {
    EXPECT_EQ(sa[k].name, sb[k].name);
    EXPECT_EQ(sa[k].content_hash, sb[k].content_hash) << sa[k].name;
    const auto ca = a.load(sa[k].name), cb = b.load(sb[k].name);
    ASSERT_EQ(ca.samples.size(), cb.samples.size()) << sa[k].name;
    for (size_t i = 0; i < ca.samples.size(); ++i) {
      EXPECT_EQ(ca.samples[i].unit, cb.samples[i].unit) << sa[k].name << " " << i;
      EXPECT_EQ(ca.samples[i].features.values, cb.samples[i].features.values) << sa[k].name << " " << i;
      EXPECT_EQ(ca.samples[i].thumbnail, cb.samples[i].thumbnail) << sa[k].name << " " << i;
    }
    EXPECT_EQ(ca.edges, cb.edges) << sa[k].name;
    EXPECT_EQ(ca.pruned, cb.pruned) << sa[k].name;
  }
  const auto v = testing::run_proctex("catalog verify --db '" + (run / "catalog.sqlite").string() + "'", dir.path());
  EXPECT_EQ(v.exit_code, 0) << v.out << v.err;

  // Batch matching as a job array over the merged catalogue, then the index job.
  fs::create_directories(dir / "photos");
  for (const auto& [name, spec] : std::vector<std::pair<std::string, std::string>>{
           {"a.png", "checker:seed=9001"}, {"b.png", "stripes:seed=9002"}, {"c.png", "grid:seed=9003"}}) {
    const auto r = testing::run_proctex("-q render '" + spec + "' --size 128 -o '" + (dir / "photos" / name).string() + "'",
                                        dir.path());
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::ofstream(dir / "photos" / "broken.png") << "not an image";
  const Shell msub = sh(cluster.env() + "'" + kScripts + "/slurm/submit-match.sh' --shards 2 --cpus 1 --photos '" +
                            (dir / "photos").string() + "' --out '" + (dir / "matches").string() + "' --proctex '" +
                            PROCTEX_BINARY + "' -- --db '" + (run / "catalog.sqlite").string() +
                            "' --starts 1 --race 2 --evaluations 20 --candidates 3",
                        dir.path());
  ASSERT_EQ(msub.code, 0) << msub.err;
  const auto mids = split_ws(msub.out);
  ASSERT_EQ(mids.size(), 2u) << msub.out;
  ASSERT_TRUE(cluster.wait(mids[0] + "," + mids[1], 120, dir.path())) << "match jobs still queued after 120 s";
  const auto index = nlohmann::json::parse(testing::read_text(dir / "matches" / "index.json"));
  ASSERT_EQ(index["photos"].size(), 4u) << index.dump();
  for (const auto& p : index["photos"]) {
    if (p["photo"] == "broken.png") {
      EXPECT_EQ(p["status"], "error") << p.dump();
    } else {
      EXPECT_EQ(p["status"], "cached") << "matched by an array task, kept by the index job: " << p.dump();
      EXPECT_TRUE(p.contains("shader") && p.contains("similarity") && p.contains("verdict")) << p.dump();
    }
  }
  for (const char* shard : {"index-1-of-2.csv", "index-2-of-2.csv"}) EXPECT_TRUE(fs::exists(dir / "matches" / shard)) << shard;
  std::printf("Slurm test: %.1f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

}  // namespace
}  // namespace proctex
