// The joint-angle target theta_d(t) of the forearm's tracking cost (Eq. 3.3): either a
// sinusoid given by its parameters (the thesis's 0.25/0.5/1.0 Hz, +-30 deg patterns) or a
// stream of timed samples (e.g. received over CAN), interpolated linearly and held at the
// ends. Fixed capacity, no allocation.
#pragma once

#include <array>
#include <cmath>
#include <limits>

#include "hmpc/constants.hpp"

namespace hmpc::forearm {

template <typename Scalar>
class TargetTrajectory {
 public:
  static constexpr int kCapacity = 128;  // > 200 ms horizon at 4 ms per sample, with margin

  // theta_d(t) = offset + amplitude sin(2 pi f (t - t0)).
  void set_sinusoid(Scalar amplitude, Scalar frequency_hz, Scalar offset, Scalar t0) {
    mode_ = Mode::kSinusoid;
    amplitude_ = amplitude;
    frequency_ = frequency_hz;
    offset_ = offset;
    t0_ = t0;
  }

  // Holds a constant angle.
  void set_constant(Scalar angle) { set_sinusoid(Scalar(0), Scalar(0), angle, Scalar(0)); }

  // Appends a sample; times must increase. Returns false (sample dropped) otherwise or when
  // the value is not finite. The oldest sample is overwritten when the buffer is full.
  bool push_sample(Scalar time, Scalar angle) {
    if (!std::isfinite(time) || !std::isfinite(angle)) return false;
    if (mode_ != Mode::kSamples) {
      mode_ = Mode::kSamples;
      count_ = 0;
      head_ = 0;
    }
    if (count_ > 0 && !(time > sample(count_ - 1).time)) return false;
    const int slot = (head_ + count_) % kCapacity;
    samples_[slot] = {time, angle};
    if (count_ < kCapacity) {
      ++count_;
    } else {
      head_ = (head_ + 1) % kCapacity;
    }
    return true;
  }

  int sample_count() const { return mode_ == Mode::kSamples ? count_ : 0; }

  // Latest sample time, or -inf when none (the host must stream ahead of the horizon).
  Scalar last_sample_time() const {
    return count_ > 0 ? sample(count_ - 1).time : -std::numeric_limits<Scalar>::infinity();
  }

  Scalar angle(Scalar t) const {
    if (mode_ == Mode::kSinusoid) {
      using std::sin;
      return offset_ + amplitude_ * sin(Scalar(2) * kPi<Scalar> * frequency_ * (t - t0_));
    }
    if (count_ == 0) return Scalar(0);
    if (t <= sample(0).time) return sample(0).angle;
    if (t >= sample(count_ - 1).time) return sample(count_ - 1).angle;
    const int lo = segment(t);
    const Sample& a = sample(lo);
    const Sample& b = sample(lo + 1);
    return a.angle + (b.angle - a.angle) * (t - a.time) / (b.time - a.time);
  }

  // theta_d'(t) [rad/s]: the sinusoid's derivative, or the slope of the samples' segment
  // holding t (0 where the ends are held).
  Scalar rate(Scalar t) const {
    if (mode_ == Mode::kSinusoid) {
      using std::cos;
      const Scalar omega = Scalar(2) * kPi<Scalar> * frequency_;
      return amplitude_ * omega * cos(omega * (t - t0_));
    }
    if (count_ < 2 || t < sample(0).time || t >= sample(count_ - 1).time) return Scalar(0);
    const int lo = segment(t);
    const Sample& a = sample(lo);
    const Sample& b = sample(lo + 1);
    return (b.angle - a.angle) / (b.time - a.time);
  }

 private:
  enum class Mode { kSinusoid, kSamples };
  struct Sample {
    Scalar time, angle;
  };
  const Sample& sample(int i) const { return samples_[(head_ + i) % kCapacity]; }
  // Binary search for lo with sample(lo).time <= t < sample(lo + 1).time, for t inside the
  // samples' span.
  int segment(Scalar t) const {
    int lo = 0, hi = count_ - 1;
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      (sample(mid).time <= t ? lo : hi) = mid;
    }
    return lo;
  }

  Mode mode_ = Mode::kSinusoid;
  Scalar amplitude_ = 0, frequency_ = 0, offset_ = 0, t0_ = 0;
  std::array<Sample, kCapacity> samples_{};
  int head_ = 0;
  int count_ = 0;
};

}  // namespace hmpc::forearm
