// The UI-render priority of the job runner: while a UI render waits (the server's counter is
// non-zero) a running match makes no progress - it pauses between its batches so the render has
// the device and the cores - and it resumes when the render is done; a render that never ends
// cannot stall it for more than about 2 s at a time.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "server/jobs.h"
#include "tests/server/support.h"
#include "tests/support/temp_dir.h"

namespace proctex {
namespace {

using namespace proctex::testing;
using Clock = std::chrono::steady_clock;

long evaluations(server::LiveJob& live) {
  std::lock_guard lock(live.mutex);
  return live.progress.value("evaluations", 0L);
}

std::string stage(server::LiveJob& live) {
  std::lock_guard lock(live.mutex);
  return live.progress.value("stage", "");
}

void sleep_s(double s) { std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(s * 1000))); }

TEST(JobsPriority, AMatchPausesBetweenBatchesWhileAUiRenderWaitsAndResumesAfter) {
  TempDir dir;
  server::JobStore store(dir / "data");
  server::RunnerOptions ro;
  ro.catalog = test_catalog();
  ro.ui_renders = std::make_shared<std::atomic<int>>(0);
  server::JobRunner runner(store, ro);
  const auto job = store.create("match", {{"options", {{"budget", "60s"}, {"evaluations", 1000000}}}, {"input", "input.png"}});
  fs::copy_file(brick_photo(), store.job_dir(job.id) / "input.png");
  runner.enqueue(job.id);
  auto live = runner.live(job.id);
  ASSERT_TRUE(live);

  // Into the refinement (evaluations are counted there, batch by batch).
  const auto deadline = Clock::now() + std::chrono::seconds(60);
  while (Clock::now() < deadline && !(evaluations(*live) > 0 && (stage(*live).rfind("race", 0) == 0 || stage(*live).rfind("refine", 0) == 0)))
    sleep_s(0.02);
  ASSERT_GT(evaluations(*live), 0) << "the match did not reach its refinement: " << stage(*live);

  *ro.ui_renders = 1;  // a UI render is waiting
  sleep_s(0.8);        // the batch in flight ends
  const long paused_at = evaluations(*live);
  sleep_s(1.0);
  EXPECT_EQ(evaluations(*live), paused_at) << "the match went on while a UI render waited";

  *ro.ui_renders = 0;  // the render is done
  sleep_s(1.0);
  const long resumed = evaluations(*live);
  EXPECT_GT(resumed, paused_at) << "the match did not resume";

  // A render that never ends: the match still moves on after the 2 s bound.
  *ro.ui_renders = 1;
  sleep_s(3.0);
  EXPECT_GT(evaluations(*live), resumed) << "a stuck UI render stalled the match";
  *ro.ui_renders = 0;

  ASSERT_TRUE(runner.cancel(job.id));
  runner.wait(job.id, 120);
  const auto done = store.get(job.id);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->state, "cancelled");
  EXPECT_FALSE(done->result.is_null()) << "a cancelled match keeps its best so far";
}

}  // namespace
}  // namespace proctex
