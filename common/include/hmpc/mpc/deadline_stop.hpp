// Truncating an MPC solve at its sampling time (thesis Sec. 2.6.3: "the MPC computations
// were truncated at the sampling time"), as the stop predicate of IlqrSolver::solve.
//
// Called before each iteration, it stops the solve when the layer's longest iteration would
// no longer end before the deadline, so that a solve ends within its time instead of
// overrunning it by its last iteration. The prediction carries over between updates
// (IterationTime): a layer's first iteration of an update is predicted from the iterations
// of its previous update, so a layer that starts late (Coarse-Fast's lower layer after an
// upper layer that ran long) does not start an iteration it cannot finish. Only at the very
// first update, with nothing measured yet, a first iteration runs whenever it starts before
// the deadline. An iteration longer than predicted (its line search backtracking further
// than any before) is cut short between rollouts once the hard deadline, the end of the
// sampling period, has passed (expired(), ilqr.hpp).
#pragma once

#include <algorithm>

namespace hmpc {

// One layer's longest iteration in its last update: the prediction for the next update's
// first iteration. Zero until one is measured. An update that measures none (it stopped
// before its second iteration) halves it, so that one slow spell cannot keep a layer from
// ever iterating again.
template <class Clock>
struct IterationTime {
  typename Clock::duration longest{0};
};

template <class Clock>
class DeadlineStop {
 public:
  using TimePoint = typename Clock::time_point;
  using Duration = typename Clock::duration;

  // `enabled` false: never stops (an untruncated solve), but still measures.
  DeadlineStop(TimePoint deadline, TimePoint hard_deadline, IterationTime<Clock>& time,
               bool enabled)
      : deadline_(deadline), hard_deadline_(hard_deadline), time_(time), enabled_(enabled) {}

  // Hands this update's longest iteration (the interval between two calls is one
  // iteration) on to the next update.
  ~DeadlineStop() { time_.longest = measured_ > Duration{0} ? measured_ : time_.longest / 2; }
  DeadlineStop(const DeadlineStop&) = delete;
  DeadlineStop& operator=(const DeadlineStop&) = delete;

  bool operator()() {
    const TimePoint now = Clock::now();
    if (started_) measured_ = std::max(measured_, now - last_);
    started_ = true;
    last_ = now;
    return enabled_ && now + std::max(measured_, time_.longest) >= deadline_;
  }
  bool expired() const { return enabled_ && Clock::now() >= hard_deadline_; }

 private:
  TimePoint deadline_, hard_deadline_, last_{};
  IterationTime<Clock>& time_;
  Duration measured_{0};
  bool enabled_, started_ = false;
};

}  // namespace hmpc
