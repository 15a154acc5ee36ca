// Counts sampling periods so that a plan on a coarser grid is time-shifted (Eq. 2.22) only
// when a whole model step has elapsed.
#pragma once

namespace hmpc {

class SampleClock {
 public:
  explicit SampleClock(int samples_per_step)
      : samples_per_step_(samples_per_step > 0 ? samples_per_step : 1) {}

  void reset() { count_ = 0; }

  // Call once per sampling period; true when a model step boundary has been crossed.
  bool advance() {
    if (++count_ < samples_per_step_) return false;
    count_ = 0;
    return true;
  }

 private:
  int samples_per_step_;
  int count_ = 0;
};

}  // namespace hmpc
