// The thread pool of the humanoid's parallel linearisation (thread_pool.hpp), on its own so that
// the ThreadSanitizer preset checks it without building the humanoid: every index run exactly
// once, tasks really concurrent, and many jobs in a row each seeing the previous one's writes
// (the hand-over between the calling thread and the workers).
#include "hmpc/humanoid/thread_pool.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

namespace {

using hmpc::humanoid::ThreadPool;

TEST(ThreadPool, RunsEveryIndexExactlyOnce) {
  for (int threads : {1, 2, 4}) {
    ThreadPool pool(threads);
    EXPECT_EQ(pool.threads(), threads);
    for (int count : {0, 1, 3, 100}) {
      std::vector<std::atomic<int>> runs(count);
      for (int repeat = 0; repeat < 3; ++repeat) pool.for_each(count, [&](int i) { ++runs[i]; });
      for (int i = 0; i < count; ++i)
        EXPECT_EQ(runs[i].load(), 3) << threads << " threads, index " << i << " of " << count;
    }
  }
}

TEST(ThreadPool, RunsTasksConcurrently) {
  // Two tasks that each wait (up to 10 s) for the other to start can only both see the other
  // if they run at the same time.
  ThreadPool pool(2);
  std::atomic<int> started{0};
  std::atomic<int> met{0};
  pool.for_each(2, [&](int) {
    ++started;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (started.load() < 2 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::yield();
    if (started.load() == 2) ++met;
  });
  EXPECT_EQ(met.load(), 2);
}

// As the MPC uses it: each job's tasks write their own slots of plain (non-atomic) memory, and
// the next job, on whichever threads, reads what the previous one wrote: its writes must be
// visible once for_each returns. Each job adds one to its neighbour's value of the job before.
TEST(ThreadPool, EachJobSeesThePreviousJobsResults) {
  ThreadPool pool(2);
  constexpr int kSlots = 16;
  constexpr int kJobs = 500;
  std::vector<long> current(kSlots, 0), next(kSlots, 0);
  for (int job = 0; job < kJobs; ++job) {
    pool.for_each(kSlots, [&](int i) { next[i] = current[(i + 1) % kSlots] + 1; });
    current.swap(next);
  }
  for (long v : current) EXPECT_EQ(v, kJobs);
}

}  // namespace
