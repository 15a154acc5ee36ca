// A small fixed pool of threads for the iLQR's per-step linearisations (thesis Sec. 2.6.2:
// "derivatives of dynamics and costs were computed in parallel", there with OpenMP).
//
// The threads are created once, by the constructor; for_each() then allocates nothing: the
// task is passed by address with a plain function pointer (no std::function), and the threads
// wait on a condition variable between calls. Indices are handed out one at a time from an
// atomic counter, so a slow step does not hold up the others; which thread runs which index
// varies, so a task's result must depend only on its index (the humanoid problems give every
// step its own workspace, which makes parallel results bit-identical to serial ones).
//
// Host only: common/ stays thread-free for the bare-metal builds (for_each_step in
// hmpc/solver/problem.hpp is the hook through which a problem hands its steps to a pool).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace hmpc::humanoid {

class ThreadPool {
 public:
  // `threads` >= 1 counts the calling thread, which works too: threads - 1 are started.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  // Runs task(i) for i = 0..count-1 on the pool and the calling thread; returns when all are
  // done. Not reentrant: one for_each at a time.
  template <class Task>
  void for_each(int count, const Task& task) {
    run(
        count, [](const void* context, int i) { (*static_cast<const Task*>(context))(i); }, &task);
  }

 private:
  using Call = void (*)(const void*, int);
  void run(int count, Call call, const void* context);
  void work();  // takes indices until none are left
  void worker_loop();

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  // The current job, written under mutex_ before generation_ changes.
  Call call_ = nullptr;
  const void* context_ = nullptr;
  int count_ = 0;
  std::atomic<int> next_{0};
  int busy_ = 0;  // workers not yet finished with the current job
  std::uint64_t generation_ = 0;
  bool stopping_ = false;
};

// Runs task(i) for i = 0..count-1 on `pool`, or in order on the calling thread if it is null.
template <class Task>
void run_on(ThreadPool* pool, int count, const Task& task) {
  if (pool != nullptr) {
    pool->for_each(count, task);
  } else {
    for (int i = 0; i < count; ++i) task(i);
  }
}

// Line-search lanes for a problem on `pool` (hmpc/solver/problem.hpp's rollout_lanes): the
// `wanted` number when the pool has a second thread to run them on, else 1.
inline int rollout_lanes_on(const ThreadPool* pool, int wanted) {
  return pool != nullptr && pool->threads() > 1 ? wanted : 1;
}

}  // namespace hmpc::humanoid
