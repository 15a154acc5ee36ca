// Fuzz target for the check every DDS command sample passes before the host acts on it
// (hmpc::dds::validate). A deserialised sample can hold any bit pattern in any field (the wire
// carries enumerations as plain octets and doubles as IEEE-754 words), so the input bytes fill
// the fields as they are: node, sequence number, mode, strategy, clear-faults, target kind, then
// the target's four doubles. Properties: an accepted command is one the board may act on (every
// enumeration a listed value, every number finite and inside command_limits(), the target
// inside the board's joint limits); a rejected one says why, naming a field.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "hmpc/dds/forearm_dds.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;

constexpr std::size_t kBytes = 1 + 4 + 1 + 1 + 1 + 1 + 4 * 8;

[[noreturn]] void fail(const char* what) {
  std::fprintf(stderr, "DDS command fuzz: %s\n", what);
  std::abort();
}

bool within(double v, double lo, double hi) { return std::isfinite(v) && v >= lo && v <= hi; }

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::uint8_t b[kBytes] = {};
  if (size > 0) std::memcpy(b, data, size < kBytes ? size : kBytes);
  dds::ForearmCommandSample c;
  std::size_t at = 0;
  c.node = b[at++];
  std::memcpy(&c.sequence_number, b + at, 4);
  at += 4;
  c.mode = static_cast<proto::RequestedMode>(b[at++]);
  c.strategy = static_cast<proto::Strategy>(b[at++]);
  c.clear_faults = (b[at++] & 1) != 0;
  c.target.kind = static_cast<dds::TargetKind>(b[at++]);
  for (double* field : {&c.target.amplitude_rad, &c.target.frequency_hz, &c.target.offset_rad,
                        &c.target.duration_s}) {
    std::memcpy(field, b + at, 8);
    at += 8;
  }

  const dds::ValidationResult result = dds::validate(c);
  if (!result.ok) {
    if (result.reason.empty()) fail("rejected without a reason");
    return 0;
  }
  const dds::CommandLimits& limits = dds::command_limits();
  const auto mode = static_cast<unsigned>(c.mode);
  if (c.node > proto::kMaxNodeId) fail("accepted a node outside the bus's");
  if (mode < static_cast<unsigned>(proto::RequestedMode::kIdle) ||
      mode > static_cast<unsigned>(proto::RequestedMode::kRun)) {
    fail("accepted an unknown mode");
  }
  if (static_cast<unsigned>(c.strategy) > static_cast<unsigned>(proto::Strategy::kPamOnly)) {
    fail("accepted an unknown strategy");
  }
  if (static_cast<unsigned>(c.target.kind) > static_cast<unsigned>(dds::TargetKind::kSinusoid)) {
    fail("accepted an unknown target kind");
  }
  if (!within(c.target.amplitude_rad, 0, limits.max_amplitude_rad) ||
      !within(c.target.frequency_hz, 0, limits.max_frequency_hz) ||
      !within(c.target.offset_rad, -limits.max_abs_offset_rad, limits.max_abs_offset_rad) ||
      !within(c.target.duration_s, 0, limits.max_duration_s)) {
    fail("accepted a target number that is not finite or out of its range");
  }
  if (c.target.offset_rad - c.target.amplitude_rad < limits.theta_min_rad ||
      c.target.offset_rad + c.target.amplitude_rad > limits.theta_max_rad) {
    fail("accepted a target beyond the board's joint limits");
  }
  return 0;
}

#ifdef HMPC_FUZZ_REPLAY
#include "fuzz_replay.hpp"

// Seeds: valid commands of every mode and kind, with the special doubles a sender may put in.
int main(int argc, char** argv) {
  using hmpc::fuzz::Bytes;
  std::vector<Bytes> seeds;
  const double specials[] = {0.0, 0.5, 1.0, -0.0, 1e300, NAN, INFINITY, -INFINITY, 5e-324};
  for (std::uint8_t mode = 1; mode <= 3; ++mode) {
    for (std::uint8_t kind = 0; kind <= 1; ++kind) {
      for (double special : specials) {
        const double fields[] = {0.3, 1.0, 0.2, special};
        Bytes b{3, 1, 0, 0, 0, mode, 4, 1, kind};
        for (double f : fields) {
          std::uint8_t raw[8];
          std::memcpy(raw, &f, 8);
          for (const std::uint8_t byte : raw) b.push_back(byte);
        }
        seeds.push_back(b);
      }
    }
  }
  return hmpc::fuzz::replay(argc, argv, "dds_command_fuzz_replay", seeds, 100, 2000);
}
#endif
