// Fault injection on outgoing CAN frames, for the HIL: frames lost or with a bit flipped, at
// random with a seeded generator (a run is reproducible), and windows of silence. The plant
// node applies it to its sensor frames (encoder or ADC dropouts, glitches), the host controller
// to its frames to the board (a lossy or interrupted bus).
#pragma once

#include <cmath>
#include <cstdint>
#include <random>
#include <string>

#include "hmpc/protocol/forearm_protocol.hpp"

namespace hmpc::platform {

struct FaultConfig {
  double drop_fraction = 0;     // share of frames lost, [0, 1]
  double corrupt_fraction = 0;  // share of frames with one bit flipped, [0, 1]
  double silence_start_s = -1;  // start of a window with no frames at all; < 0: none
  double silence_duration_s = 0;
  std::uint64_t seed = 1;

  bool any() const { return drop_fraction > 0 || corrupt_fraction > 0 || silence_start_s >= 0; }
  // Empty when valid, otherwise what is wrong.
  std::string check() const {
    const auto fraction_ok = [](double f) { return std::isfinite(f) && f >= 0 && f <= 1; };
    if (!fraction_ok(drop_fraction)) return "drop fraction must be in [0, 1]";
    if (!fraction_ok(corrupt_fraction)) return "corrupt fraction must be in [0, 1]";
    if (!std::isfinite(silence_start_s)) return "silence start must be finite";
    if (!std::isfinite(silence_duration_s) || silence_duration_s < 0)
      return "silence duration must be a finite number >= 0";
    return {};
  }
};

struct FaultCounters {
  std::uint64_t passed = 0, dropped = 0, corrupted = 0, silenced = 0;
};

enum class FaultAction { kPass, kDrop };

class FaultInjector {
 public:
  explicit FaultInjector(const FaultConfig& config) : config_(config), random_(config.seed) {}

  // Decides the fate of `frame`, sent at time_s: kDrop (not to be sent) or kPass, in which
  // case the frame may have had one bit of its payload flipped. A flipped bit is caught by the
  // receiver's CRC-8, which detects every single-bit error.
  FaultAction apply(double time_s, forearm_protocol::Frame& frame) {
    if (in_silence(time_s)) {
      ++counters_.silenced;
      return FaultAction::kDrop;
    }
    if (config_.drop_fraction > 0 && uniform_(random_) < config_.drop_fraction) {
      ++counters_.dropped;
      return FaultAction::kDrop;
    }
    if (config_.corrupt_fraction > 0 && frame.dlc > 0 &&
        uniform_(random_) < config_.corrupt_fraction) {
      const std::uint32_t bit = std::uint32_t(random_() % (8u * frame.dlc));
      frame.data[bit / 8] = std::uint8_t(frame.data[bit / 8] ^ (1u << (bit % 8)));
      ++counters_.corrupted;
    }
    ++counters_.passed;
    return FaultAction::kPass;
  }

  bool in_silence(double time_s) const {
    return config_.silence_start_s >= 0 && time_s >= config_.silence_start_s &&
           time_s < config_.silence_start_s + config_.silence_duration_s;
  }
  const FaultCounters& counters() const { return counters_; }

 private:
  FaultConfig config_;
  std::mt19937_64 random_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  FaultCounters counters_;
};

}  // namespace hmpc::platform
