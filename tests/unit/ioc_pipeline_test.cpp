// The whole of Sec. 4.2 on the human demonstrator (demonstrator.hpp): captures of jumping and
// squatting under hidden weights, retargeted and tracked on the robot (retargeting.hpp),
// learned (learn.hpp), and each task generated with the learned and with the initial weights.
// Six captures a task instead of the thesis's 40 (minutes otherwise); label long.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "hmpc/humanoid/physical_checks.hpp"
#include "hmpc/ioc/learn.hpp"
#include "hmpc/ioc/retargeting.hpp"

namespace {

using namespace hmpc;
using namespace hmpc::ioc;

constexpr int kCaptures = 6;

struct Task {
  Weights hidden;  // the demonstrator's
  Weights learned;
  humanoid::Motion reference;  // the demonstrated behaviour's targets, the robot task's weights
};

// RMS over a demonstration's states and leg joints of the joint angles' distance from their
// first values [rad] (q = base position, quaternion, joints).
double joint_excursion(const Demonstration& d) {
  constexpr int kJointOffset = 7;
  double sum = 0.0;
  for (const humanoid::StateVector& x : d.states) {
    sum += (x.segment<humanoid::kLegJoints>(kJointOffset) -
            d.states.front().segment<humanoid::kLegJoints>(kJointOffset))
               .squaredNorm();
  }
  return std::sqrt(sum / (humanoid::kLegJoints * double(d.states.size())));
}

Task learn_task(const std::string& demonstrator, const std::string& task, TimeWarping warping) {
  SCOPED_TRACE(demonstrator);
  const humanoid::Motion human =
      humanoid::load_motion(std::string(HMPC_IOC_DEMONSTRATORS) + "/" + demonstrator);
  const humanoid::Motion robot =
      humanoid::load_motion(std::string(HMPC_HUMANOID_MOTIONS) + "/" + task);
  CaptureConfig capture;
  capture.count = kCaptures;
  const std::vector<Capture> captures = capture_demonstrations(human, capture);
  // The demonstrator, an MPC, may fall (measured: 1 jump in 8); most performances stand.
  EXPECT_GE(captures.size(), static_cast<std::size_t>(kCaptures - 1));
  RetargetConfig retargeting;
  retargeting.warping = warping;
  const Retargeted r = retarget(captures, robot, retargeting);
  std::vector<Demonstration> demonstrations;
  for (const TrackedDemonstration& t : r.tracked) {
    if (t.fell) continue;
    // The tracking reproduces the captured joint motion: its RMS joint error is at most half
    // the motion's own RMS excursion from its first posture, i.e. it follows at least three
    // quarters of the motion's power (standing still would score an error of one excursion).
    const double excursion = joint_excursion(t.demonstration);
    EXPECT_LT(t.errors.joints, 0.5 * excursion) << "excursion " << excursion << " rad";
    demonstrations.push_back(t.demonstration);
  }
  EXPECT_GE(demonstrations.size(), captures.size() - 1);
  humanoid::ThreadPool pool(2);
  const LocalIoc ioc(r.reference, demonstrations, &pool);
  // As hmpc-ioc learn does by default.
  LearnConfig learning;
  learning.estimator = Estimator::kLeastExcessCost;
  learning.lbfgs.max_iterations = 200;
  const LearnResult result = learn_weights(ioc, learning);
  // The demonstrations' excess cost falls below the initial weights' at the same geometric mean
  // (the common scale the estimator holds).
  const double scale = std::exp(result.weights.array().log().mean());
  EXPECT_LT(ioc.excess_cost(result.weights), ioc.excess_cost(scale * initial_weights()));
  return {weights_of(human.weights), result.weights, r.reference};
}

// RMS of log(w / hidden) over the torque weights, up to a common scale (IOC's weights have
// none): 0 when the proportions are the hidden ones.
double torque_proportion_error(const Weights& w, const Weights& hidden) {
  const Eigen::Array4d log_ratio =
      (w.head<kControlWeights>().array() / hidden.head<kControlWeights>().array()).log();
  return std::sqrt((log_ratio - log_ratio.mean()).square().mean());
}

// The Coarse-Fast MPC's run (untruncated: the same on any machine) of the demonstrated
// behaviour with `weights`.
humanoid::ClosedLoopRun generate(const Task& task, const Weights& weights) {
  humanoid::ClosedLoopConfig config;
  config.truncate = false;
  humanoid::Motion m = task.reference;
  m.weights = with_weights(m.weights, weights);
  return humanoid::run_closed_loop(m, config);
}

void expect_learned_beats_initial(const Task& task) {
  // The torque weights' proportions come nearer the demonstrator's than the initial (equal)
  // ones. The state weights come out too small relative to them (local IOC reads a
  // demonstration's distance from a local optimum as weaker state costs); not asserted.
  EXPECT_LT(torque_proportion_error(task.learned, task.hidden),
            torque_proportion_error(initial_weights(), task.hidden));
  // Figs. 4.4-4.5: the motion generated with the learned weights is nearer the demonstrated
  // one than with the initial weights (with which the robot falls).
  const MotionErrors initial = motion_errors(task.reference, generate(task, initial_weights())),
                     learned = motion_errors(task.reference, generate(task, task.learned));
  EXPECT_LT(learned.height, initial.height);
  EXPECT_LT(learned.attitude, initial.attitude);
  EXPECT_LT(learned.velocity, initial.velocity);
}

// One test for both tasks: the last check compares what they learned (tests run in separate
// processes, so two tests would learn each task twice).
TEST(IocPipeline, JumpingAndSquattingFromTheHumanDemonstrator) {
  // Each task with the time warping measured better for it (README): the jump's timeline bent
  // by the feasibility index, the squat's Froude's.
  const Task jumping = learn_task("jumping.motion", "V-low-jump.motion", TimeWarping::kFeasibility);
  const Task squatting = learn_task("squatting.motion", "squatting.motion", TimeWarping::kFroude);
  for (const Task* task : {&jumping, &squatting}) {
    std::printf("%-9s %12s %12s\n", task == &jumping ? "jumping" : "squatting", "learned",
                "hidden");
    for (int k = 0; k < kWeightCount; ++k) {
      std::printf("%-9s %12.4g %12.4g\n", kWeightNames[k], task->learned[k], task->hidden[k]);
    }
  }
  {
    SCOPED_TRACE("jumping");
    expect_learned_beats_initial(jumping);
  }
  {
    SCOPED_TRACE("squatting");
    expect_learned_beats_initial(squatting);
  }
  // Sec. 4.3.2: the learned weights generate the demonstrated behaviour. The jump leaves the
  // ground (a flight as the jumps' physical check counts one, 60 ms) and peaks within 3 cm of
  // the demonstrated apex; the squat goes within 2 cm of the demonstrated depth. (The squat's
  // tracked demonstrations rise off the ground as they stand up, flights of up to 120 ms, so
  // the learned squat may too: not checked.)
  const humanoid::ClosedLoopRun jump = generate(jumping, jumping.learned);
  const humanoid::ClosedLoopRun squat = generate(squatting, squatting.learned);
  const HeightRange jump_targets = target_heights(jumping.reference),
                    squat_targets = target_heights(squatting.reference);
  std::printf(
      "learned jump: flight %.0f ms, apex %.3f m (demonstrated %.3f m); learned squat: "
      "lowest %.3f m (demonstrated %.3f m)\n",
      1e3 * humanoid::longest_flight(jump), humanoid::apex_height(jump), jump_targets.highest,
      humanoid::lowest_height(squat), squat_targets.lowest);
  EXPECT_GE(humanoid::longest_flight(jump), 0.06 - 1e-9);
  EXPECT_NEAR(humanoid::apex_height(jump), jump_targets.highest, 0.03);
  EXPECT_NEAR(humanoid::lowest_height(squat), squat_targets.lowest, 0.02);
  // Jumping and squatting learn different weights: not the same up to scale (the threshold for
  // that is a cosine similarity of 0.95; both start from the initial weights, cosine 1;
  // measured 0.82), and the torque weights' proportions differ between the tasks the way the
  // demonstrator's do: the learned jumping / squatting ratios are nearer the hidden ones than
  // equal proportions are (measured 0.26 against 0.36). Each task's learned torque proportions
  // are not always nearer its own demonstrator's than the other task's, and the state weights'
  // differences do not follow the hidden ones (they come out too small, as above): neither is
  // asserted.
  const double cosine = cosine_similarity(jumping.learned, squatting.learned);
  const Weights hidden_ratio = jumping.hidden.cwiseQuotient(squatting.hidden);
  const double ratio_error =
      torque_proportion_error(jumping.learned.cwiseQuotient(squatting.learned), hidden_ratio);
  const double equal_error = torque_proportion_error(Weights::Ones(), hidden_ratio);
  std::printf(
      "cosine similarity of the learned weights, jumping to squatting: %.3f\n"
      "torque proportions, jumping / squatting: learned %.3f from the hidden, equal ones %.3f\n",
      cosine, ratio_error, equal_error);
  EXPECT_LT(cosine, 0.95);
  EXPECT_LT(ratio_error, equal_error);
}

}  // namespace
