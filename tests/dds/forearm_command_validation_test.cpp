// validate() of forearm commands (host/dds): no DDS involved.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include "forearm_board.hpp"
#include "hmpc/dds/forearm_dds.hpp"

namespace {

namespace dds = hmpc::dds;
namespace proto = hmpc::forearm_protocol;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// The thesis's fastest tracking pattern (Sec. 3.3): 30 deg at 1 Hz, here around 0.2 rad.
dds::ForearmCommandSample good_command() {
  dds::ForearmCommandSample c;
  c.node = 3;
  c.sequence_number = 17;
  c.mode = proto::RequestedMode::kRun;
  c.strategy = proto::Strategy::kTwoStage;
  c.target.kind = dds::TargetKind::kSinusoid;
  c.target.amplitude_rad = 0.5236;
  c.target.frequency_hz = 1.0;
  c.target.offset_rad = 0.2;
  c.target.duration_s = 10;
  return c;
}

TEST(ForearmCommandValidation, AcceptsAGoodCommand) {
  const dds::ValidationResult result = dds::validate(good_command());
  EXPECT_TRUE(result.ok) << result.reason;
  EXPECT_TRUE(result.reason.empty());
}

TEST(ForearmCommandValidation, AcceptsEveryModeStrategyAndKind) {
  for (auto mode :
       {proto::RequestedMode::kIdle, proto::RequestedMode::kHold, proto::RequestedMode::kRun}) {
    for (const proto::EnumValue& strategy : proto::kStrategyValues) {
      for (auto kind : {dds::TargetKind::kHoldCurrent, dds::TargetKind::kSinusoid}) {
        dds::ForearmCommandSample c = good_command();
        c.mode = mode;
        c.strategy = static_cast<proto::Strategy>(strategy.value);
        c.target.kind = kind;
        EXPECT_TRUE(dds::validate(c).ok) << strategy.name << ": " << dds::validate(c).reason;
      }
    }
  }
  EXPECT_TRUE(dds::validate(dds::ForearmCommandSample{}).ok) << "the default is idle, hold";
}

TEST(ForearmCommandValidation, AcceptsTheEndsOfEveryRange) {
  const dds::CommandLimits& limits = dds::command_limits();
  dds::ForearmCommandSample c = good_command();
  c.node = proto::kMaxNodeId;
  c.target.amplitude_rad = limits.theta_max_rad - limits.max_abs_offset_rad;
  c.target.offset_rad = limits.max_abs_offset_rad;
  c.target.frequency_hz = limits.max_frequency_hz;
  c.target.duration_s = limits.max_duration_s;
  EXPECT_TRUE(dds::validate(c).ok) << dds::validate(c).reason;
  c.target = {};
  c.target.kind = dds::TargetKind::kSinusoid;
  c.target.offset_rad = -limits.max_abs_offset_rad;
  c.target.amplitude_rad = -limits.theta_min_rad - limits.max_abs_offset_rad;
  ASSERT_GT(c.target.amplitude_rad, 0);
  EXPECT_TRUE(dds::validate(c).ok) << dds::validate(c).reason;
}

// The joint range is the board's own, not a copy that could drift from it.
TEST(ForearmCommandValidation, JointLimitsAreTheBoardsSoftwareLimits) {
  const hmpc::firmware::BoardConfig<double> board{};
  EXPECT_EQ(dds::command_limits().theta_min_rad, board.theta_min);
  EXPECT_EQ(dds::command_limits().theta_max_rad, board.theta_max);
  EXPECT_LT(board.theta_min, 0);
  EXPECT_GT(board.theta_max, 0);
}

struct BadCase {
  const char* what;
  std::function<void(dds::ForearmCommandSample&)> spoil;
  const char* field;  // the reason must name it
};

TEST(ForearmCommandValidation, RejectsEachBadFieldNamingIt) {
  const BadCase cases[] = {
      {"node past 15", [](auto& c) { c.node = 16; }, "node"},
      {"no mode", [](auto& c) { c.mode = static_cast<proto::RequestedMode>(0); }, "mode"},
      {"mode past run", [](auto& c) { c.mode = static_cast<proto::RequestedMode>(4); }, "mode"},
      {"strategy past PAM-only", [](auto& c) { c.strategy = static_cast<proto::Strategy>(6); },
       "strategy"},
      {"strategy 255", [](auto& c) { c.strategy = static_cast<proto::Strategy>(255); }, "strategy"},
      {"target kind 2", [](auto& c) { c.target.kind = static_cast<dds::TargetKind>(2); },
       "target.kind"},
      {"NaN amplitude", [](auto& c) { c.target.amplitude_rad = kNaN; }, "target.amplitude_rad"},
      {"negative amplitude", [](auto& c) { c.target.amplitude_rad = -0.1; },
       "target.amplitude_rad"},
      {"amplitude past 1 rad",
       [](auto& c) {
         c.target.amplitude_rad = 1.01;
         c.target.offset_rad = 0.1;
       },
       "target.amplitude_rad"},
      {"infinite frequency", [](auto& c) { c.target.frequency_hz = kInf; }, "target.frequency_hz"},
      {"negative frequency", [](auto& c) { c.target.frequency_hz = -1; }, "target.frequency_hz"},
      {"frequency past 5 Hz", [](auto& c) { c.target.frequency_hz = 5.01; }, "target.frequency_hz"},
      {"NaN offset", [](auto& c) { c.target.offset_rad = kNaN; }, "target.offset_rad"},
      {"offset past 1 rad", [](auto& c) { c.target.offset_rad = -1.01; }, "target.offset_rad"},
      {"negative duration", [](auto& c) { c.target.duration_s = -1; }, "target.duration_s"},
      {"duration past an hour", [](auto& c) { c.target.duration_s = 3600.5; }, "target.duration_s"},
      {"infinite duration", [](auto& c) { c.target.duration_s = -kInf; }, "target.duration_s"},
      {"sinusoid above the joint limit",
       [](auto& c) {
         c.target.offset_rad = 1.0;
         c.target.amplitude_rad = 0.7;
       },
       "joint limits"},
      {"sinusoid below the joint limit",
       [](auto& c) {
         c.target.offset_rad = -0.8;
         c.target.amplitude_rad = 0.5;
       },
       "joint limits"},
      // Unused fields are checked too: garbage there means a broken sender.
      {"NaN amplitude of a hold-current target",
       [](auto& c) {
         c.target.kind = dds::TargetKind::kHoldCurrent;
         c.target.amplitude_rad = kNaN;
       },
       "target.amplitude_rad"},
  };
  for (const BadCase& bad : cases) {
    dds::ForearmCommandSample c = good_command();
    bad.spoil(c);
    const dds::ValidationResult result = dds::validate(c);
    EXPECT_FALSE(result.ok) << bad.what;
    EXPECT_NE(result.reason.find(bad.field), std::string::npos)
        << bad.what << ": reason '" << result.reason << "' does not name " << bad.field;
  }
}

TEST(ForearmCommandValidation, ReasonSaysTheValueAndTheRange) {
  dds::ForearmCommandSample c = good_command();
  c.target.frequency_hz = 7.5;
  EXPECT_EQ(dds::validate(c).reason, "target.frequency_hz 7.5 is outside 0..5 Hz");
  c = good_command();
  c.strategy = static_cast<proto::Strategy>(9);
  EXPECT_NE(dds::validate(c).reason.find("strategy 9 "), std::string::npos)
      << dds::validate(c).reason;
}

}  // namespace
