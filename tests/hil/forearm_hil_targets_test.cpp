// Targets other than the thesis's sinusoids in the forearm HIL over CAN (board, host and Simbody
// plant in lock-step on vcan0, with the demo's mismatch and noise): a rate-limited step and a
// trajectory from a CSV file are tracked by the Two-stage MPC, the offset-free MPC holds a
// constant target on mismatched plants, and a target the joint cannot follow is refused before
// any program starts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "forearm_hil_support.hpp"
#include "hmpc/models/forearm_target_range.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::hil::HilRunResult;
using hmpc::hil::HilRunSpec;
using hmpc::hil::PlantRow;
using hmpc::hil::test::expect_intact;
using hmpc::trajectory::TargetShape;

constexpr double kDegree = M_PI / 180;

// The target at plant time t of the run, from the same points the host streamed.
struct TargetCurve {
  explicit TargetCurve(const HilRunSpec& s, const HilRunResult& r)
      : target(hmpc::trajectory::kMaxPoints) {
    hmpc::trajectory::TargetSpec spec = s.target;
    spec.duration_s = s.run_for_s;
    std::vector<hmpc::trajectory::TrajectoryPoint> points;
    std::string error;
    EXPECT_TRUE(hmpc::trajectory::make_points(spec, hmpc::forearm::target_range(),
                                              hmpc::trajectory::kMaxPoints, points, error))
        << error;
    target.assign(points.data(), points.size());
    t0 = r.number(r.host, "run_start_s");
  }
  double operator()(double t) const { return target.position(t - t0); }
  hmpc::trajectory::JointTrajectoryTarget target;
  double t0 = 0;
};

// The largest |theta - theta_d| over the plant's rows in [from, to] (run time, s).
double worst_error(const HilRunResult& r, const TargetCurve& theta_d, double from, double to) {
  double worst = 0;
  for (const PlantRow& row : r.plant_log) {
    const double t = row.time - theta_d.t0;
    if (t >= from && t <= to) worst = std::max(worst, std::abs(row.theta - theta_d(row.time)));
  }
  return worst;
}

// The host streamed this target, not another: its log's theta_d (column 6, 5 decimals) at each
// telemetry report is the target's, on the host clock the run started by.
void expect_streamed(const HilRunSpec& s, const TargetCurve& theta_d) {
  std::ifstream log(s.directory + "/host.csv");
  std::string line;
  std::getline(log, line);
  int compared = 0;
  double worst = 0;
  while (std::getline(log, line)) {
    std::vector<std::string> fields;
    std::stringstream row(line);
    for (std::string field; std::getline(row, field, ',');) fields.push_back(field);
    ASSERT_GE(fields.size(), 6u) << line;
    const double t = std::stod(fields[0]), logged = std::stod(fields[5]);
    if (std::isnan(logged)) continue;
    worst = std::max(worst, std::abs(logged - theta_d(t)));
    ++compared;
  }
  EXPECT_GT(compared, int(s.run_for_s / 0.004) / 2);
  EXPECT_LE(worst, 1e-5);
}

// A 30 deg step at 1 s, at the default 180 deg/s: from half a second after the target stops
// (the MPC's longest horizon of Table 3.1 is 200 ms, the valve's pressure settles in a few of its
// time constants) the joint stays within the 2 % band conventional for settling, 0.6 deg.
TEST(ForearmHilTargets, ARateLimitedStepIsTrackedIntoItsSettlingBand) {
  HilRunSpec s = hmpc::hil::test::spec(proto::Strategy::kTwoStage, "target_step");
  s.target.shape = TargetShape::kStep;
  s.target.amplitude = 30 * kDegree;
  s.target.step_at_s = 1;
  s.target.step_rate = M_PI;
  s.run_for_s = 3;
  const HilRunResult r = hmpc::hil::run_hil(s, hmpc::hil::HilPrograms::built());
  expect_intact(r, s);
  ASSERT_TRUE(r.ok) << r.error;
  const TargetCurve theta_d(s, r);
  const double settled_from = s.target.step_at_s + s.target.amplitude / s.target.step_rate + 0.5;
  const double settled = worst_error(r, theta_d, settled_from, s.run_for_s);
  std::printf("step: worst error %.3f deg from %.2f s; RMS over the run %.3f deg\n",
              settled / kDegree, settled_from, r.rms_error / kDegree);
  EXPECT_LE(settled, 0.02 * s.target.amplitude);
  expect_streamed(s, theta_d);
}

// A trajectory only a file can give: a minimum-jerk rise with its velocities (cubic Hermite), a
// hold, a straight return through zero, a hold. Tracked within 5 % of its 34 deg range RMS, and
// after its last move within the 2 % settling band of that move (0.6 rad).
TEST(ForearmHilTargets, ACsvTrajectoryIsTracked) {
  HilRunSpec s = hmpc::hil::test::spec(proto::Strategy::kTwoStage, "target_csv");
  std::filesystem::create_directories(hmpc::hil::test::work_dir());
  const std::string file = hmpc::hil::test::work_dir() + "/target.csv";
  {
    std::ofstream csv(file);
    csv << "time_s,position_rad,velocity_rad_s\n0,0,0\n0.5,0,0\n";
    for (int k = 1; k <= 20; ++k) {
      const double u = k / 20.0;  // 0.4 rad (10 u^3 - 15 u^4 + 6 u^5) over 1 s from 0.5 s
      csv << 0.5 + u << ","
          << 0.4 * (10 * std::pow(u, 3) - 15 * std::pow(u, 4) + 6 * std::pow(u, 5)) << ","
          << 0.4 * (30 * u * u - 60 * std::pow(u, 3) + 30 * std::pow(u, 4)) << "\n";
    }
    csv << "2.2,0.4\n2.8,-0.2\n";
  }
  s.target.shape = TargetShape::kFile;
  s.target.file = file;
  s.run_for_s = 4;
  const HilRunResult r = hmpc::hil::run_hil(s, hmpc::hil::HilPrograms::built());
  expect_intact(r, s);
  ASSERT_TRUE(r.ok) << r.error;
  const TargetCurve theta_d(s, r);
  const double range = 0.6;
  const double settled = worst_error(r, theta_d, 2.8 + 0.5, s.run_for_s);
  std::printf("csv: RMS %.3f deg, worst error %.3f deg after the last move\n",
              r.rms_error / kDegree, settled / kDegree);
  EXPECT_LE(r.rms_error, 0.05 * range);
  EXPECT_LE(settled, 0.02 * range);
  expect_streamed(s, theta_d);
}

// Offset-free MPC over CAN (the board's --offset-free) on the Simbody plant made heavier,
// stiffer in its bearing and slower in its valve than the board's model, each alone and all
// together (the plant node's largest factors, 2x, for friction; +30 % mass, +50 % valve time):
// a constant target of 17 deg, the mean error over the last 2 s of a 4 s run at most 0.1 deg.
// The thesis's MPC on the heavier plant, beside it, settles off by more.
double settled_error(const std::string& name, hmpc::hil::ForearmMismatch mismatch,
                     bool offset_free) {
  HilRunSpec s = hmpc::hil::test::spec(proto::Strategy::kTwoStage, "constant_" + name);
  s.target.shape = TargetShape::kStep;  // a step of 0: the offset, held
  s.target.amplitude = 0;
  s.target.offset = 17 * kDegree;
  s.run_for_s = 4;
  s.mismatch = mismatch;
  if (offset_free) s.board_args.push_back("--offset-free");
  const HilRunResult r = hmpc::hil::run_hil(s, hmpc::hil::HilPrograms::built());
  expect_intact(r, s);
  if (!r.ok) return NAN;
  EXPECT_EQ(r.number(r.board, "offset_free"), offset_free ? 1 : 0);
  const double t0 = r.number(r.host, "run_start_s");
  double sum = 0;
  int n = 0;
  for (const PlantRow& row : r.plant_log) {
    const double t = row.time - t0;
    if (t >= s.run_for_s - 2 && t <= s.run_for_s) {
      sum += std::abs(row.theta - s.target.offset);
      ++n;
    }
  }
  EXPECT_GT(n, 1900);
  const double error = sum / n;
  std::printf("%-22s %s: mean |error| over the last 2 s %.4f deg, disturbance estimate %s N m\n",
              name.c_str(), offset_free ? "offset-free" : "thesis     ", error / kDegree,
              r.board.count("disturbance_estimate_nm")
                  ? r.board.at("disturbance_estimate_nm").c_str()
                  : "?");
  return error;
}

TEST(ForearmHilTargets, OffsetFreeMpcHoldsAConstantTargetOnEveryMismatch) {
  const struct {
    const char* name;
    hmpc::hil::ForearmMismatch mismatch;
  } cases[] = {{"payload_30pc", {1.3, 1, 1}},
               {"friction_x2", {1, 2, 1}},
               {"valve_50pc_slower", {1, 1, 1.5}},
               {"all_three", {1.3, 2, 1.5}}};
  for (const auto& c : cases) EXPECT_LE(settled_error(c.name, c.mismatch, true), 0.1 * kDegree);
  EXPECT_GT(settled_error("payload_30pc", {1.3, 1, 1}, false), 0.1 * kDegree);
}

// A target the joint cannot follow (a chirp of 40 deg up to 2.5 Hz reaches 11 rad/s) is refused by
// the runner before it starts a program: no board ever sees it.
TEST(ForearmHilTargets, ATargetTooFastIsRefusedBeforeAnyProgramStarts) {
  HilRunSpec s = hmpc::hil::test::spec(proto::Strategy::kTwoStage, "target_too_fast");
  std::filesystem::remove_all(s.directory);
  s.target.shape = TargetShape::kChirp;
  s.target.amplitude = 40 * kDegree;
  s.target.chirp_end_hz = 2.5;
  s.run_for_s = 2;
  const HilRunResult r = hmpc::hil::run_hil(s, hmpc::hil::HilPrograms::built());
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("invalid target: "), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("beyond the joint's 10 rad/s"), std::string::npos) << r.error;
  EXPECT_FALSE(std::filesystem::exists(s.directory + "/board.out"));
}

}  // namespace
