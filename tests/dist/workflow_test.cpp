// The GitHub Actions recipe: valid against the Actions schema (@action-validator/cli from npm,
// version pinned in scripts/dist/lint/package-lock.json), and running the same scripts as the Slurm
// jobs the Slurm test submits.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <fstream>

#include "tests/support/run.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

namespace fs = std::filesystem;
const fs::path kRoot = PROCTEX_SOURCE_DIR;

struct Shell {
  int code = -1;
  std::string out, err;
};
Shell sh(const std::string& cmd, const fs::path& scratch) {
  const auto o = scratch / "sh.out", e = scratch / "sh.err";
  const int status = std::system((cmd + " >'" + o.string() + "' 2>'" + e.string() + "' </dev/null").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, testing::read_text(o), testing::read_text(e)};
}

std::string lint(const std::string& files, const fs::path& scratch, Shell* result) {
  const fs::path work = fs::path(PROCTEX_BINARY).parent_path().parent_path() / "workflow-lint";
  *result = sh("'" + (kRoot / "scripts/dist/lint-workflows.sh").string() + "' '" + work.string() + "' " + files, scratch);
  return result->out + result->err;
}

TEST(Workflow, CatalogWorkflowIsValidAndTheLinterCatchesMistakes) {
  testing::TempDir dir;
  Shell r;
  std::string log = lint("'" + (kRoot / ".github/workflows/catalog.yml").string() + "'", dir.path(), &r);
  if (r.code == 3) GTEST_SKIP() << "workflow linter not available: " << log;
  EXPECT_EQ(r.code, 0) << log;
  // The linter is real: a typo in a job and a step without run/uses are rejected.
  const std::string wf = testing::read_text(kRoot / ".github/workflows/catalog.yml");
  std::string broken = wf;
  broken.replace(broken.find("runs-on:"), 8, "runs_on:");
  std::ofstream(dir / "broken.yml") << broken;
  std::ofstream(dir / "nostep.yml") << "name: x\non: push\njobs:\n  a:\n    runs-on: ubuntu-24.04\n    steps:\n      - name: nothing\n        with: {a: 1}\n";
  log = lint("'" + (dir / "broken.yml").string() + "'", dir.path(), &r);
  EXPECT_EQ(r.code, 1) << log;
  log = lint("'" + (dir / "nostep.yml").string() + "'", dir.path(), &r);
  EXPECT_EQ(r.code, 1) << log;
}

TEST(Workflow, StepsAreTheCommandsTheSlurmJobsRun) {
  const std::string wf = testing::read_text(kRoot / ".github/workflows/catalog.yml");
  const std::string shard = testing::read_text(kRoot / "scripts/slurm/catalog-shard.sbatch");
  const std::string merge = testing::read_text(kRoot / "scripts/slurm/catalog-merge.sbatch");
  for (const char* script : {"scripts/dist/build-shard.sh", "scripts/dist/merge-shards.sh"})
    EXPECT_NE(wf.find(script), std::string::npos) << script;
  EXPECT_NE(shard.find("dist/build-shard.sh"), std::string::npos);
  EXPECT_NE(merge.find("dist/merge-shards.sh"), std::string::npos);
  // One shard job per matrix entry, each uploading its shard; the merge job publishes the catalogue.
  EXPECT_NE(wf.find("shard: [1, 2, 3, 4]"), std::string::npos);
  EXPECT_NE(wf.find("SHARDS: \"4\""), std::string::npos);
  EXPECT_NE(wf.find("name: shard-${{ matrix.shard }}"), std::string::npos);
  EXPECT_NE(wf.find("needs: shard"), std::string::npos);
  EXPECT_NE(wf.find("name: catalog\n"), std::string::npos);
}

}  // namespace
}  // namespace proctex
