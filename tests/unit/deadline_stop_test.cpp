// The truncation rule of deadline_stop.hpp, on a clock the test moves by hand (milliseconds).
#include "hmpc/mpc/deadline_stop.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>

namespace {

struct ManualClock {
  using duration = std::chrono::milliseconds;
  using rep = duration::rep;
  using period = duration::period;
  using time_point = std::chrono::time_point<ManualClock>;
  static constexpr bool is_steady = true;
  static time_point now() { return time_point(duration(ms)); }
  static inline std::int64_t ms = 0;
};

using Stop = hmpc::DeadlineStop<ManualClock>;
using Time = hmpc::IterationTime<ManualClock>;

ManualClock::time_point at(std::int64_t ms) {
  return ManualClock::time_point(ManualClock::duration(ms));
}

// Iterations of `length` ms from `first` on until the stop fires (or `cap` of them ran);
// returns how many ran.
int iterate(Stop& stop, std::int64_t first, std::int64_t length, int cap = 100) {
  ManualClock::ms = first;
  int ran = 0;
  while (ran < cap && !stop()) {
    ManualClock::ms += length;
    ++ran;
  }
  return ran;
}

TEST(DeadlineStop, RunsOnlyIterationsThatEndBeforeTheDeadline) {
  Time time;
  Stop stop(at(30), at(30), time, true);
  // Iterations of 5 ms from 1 ms: those starting at 1, 6, 11, 16, 21 end by 26; the next
  // would end at 31.
  EXPECT_EQ(iterate(stop, 1, 5), 5);
  EXPECT_LT(ManualClock::ms, 30);
}

TEST(DeadlineStop, ALateLayerSkipsAnIterationItsLastUpdateSaysWillNotFit) {
  Time time;
  {
    Stop first_update(at(30), at(30), time, true);
    EXPECT_EQ(iterate(first_update, 1, 5), 5);
  }
  EXPECT_EQ(time.longest, ManualClock::duration(5));
  // Next period (100-130 ms) the layer only gets the clock at 127 ms: a 5 ms iteration would
  // end at 132, so none starts. Without the carried time, nothing is known before the first
  // iteration and it would run past the period.
  {
    Stop late(at(130), at(130), time, true);
    EXPECT_EQ(iterate(late, 127, 5), 0);
  }
  {
    Time unknown;
    Stop late(at(130), at(130), unknown, true);
    EXPECT_EQ(iterate(late, 127, 5, 1), 1);
    EXPECT_GT(ManualClock::ms, 130);
  }
}

TEST(DeadlineStop, ThePredictionFollowsTheLastUpdate) {
  Time time;
  {
    Stop slow(at(30), at(30), time, true);
    iterate(slow, 1, 12);  // a slow spell: 12 ms iterations
  }
  EXPECT_EQ(time.longest, ManualClock::duration(12));
  {
    Stop fast(at(130), at(130), time, true);
    iterate(fast, 101, 3);
  }
  EXPECT_EQ(time.longest, ManualClock::duration(3));
}

TEST(DeadlineStop, AnUpdateWithoutIterationsHalvesThePrediction) {
  // A layer stopped before its first iteration measures nothing; were the prediction kept,
  // one slow spell could starve the layer of iterations for good.
  Time time;
  time.longest = ManualClock::duration(20);
  for (const int halved : {10, 5, 2}) {  // 125 + 20, + 10, + 5 >= 130
    {
      Stop starved(at(130), at(130), time, true);
      EXPECT_EQ(iterate(starved, 125, 1), 0);
    }
    EXPECT_EQ(time.longest, ManualClock::duration(halved));
  }
  Stop recovered(at(130), at(130), time, true);
  EXPECT_GT(iterate(recovered, 125, 1), 0);
}

TEST(DeadlineStop, DisabledNeverStopsButStillMeasures) {
  Time time;
  {
    Stop untruncated(at(30), at(30), time, false);
    EXPECT_EQ(iterate(untruncated, 1, 7, 10), 10);
    EXPECT_FALSE(untruncated.expired());
  }
  EXPECT_EQ(time.longest, ManualClock::duration(7));
}

TEST(DeadlineStop, ExpiresAtTheHardDeadline) {
  Time time;
  Stop stop(at(22), at(30), time, true);
  ManualClock::ms = 29;
  EXPECT_FALSE(stop.expired());
  ManualClock::ms = 30;
  EXPECT_TRUE(stop.expired());
}

}  // namespace
