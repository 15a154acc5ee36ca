// The closed loop's simulation of one MPC (closed_loop.hpp), shared by the files that run each
// kind: closed_loop_fine.cpp, closed_loop_coarse.cpp and closed_loop_coarse_fast.cpp each
// instantiate it for one MPC (the heaviest templates of the library, so they compile in
// parallel), closed_loop.cpp checks the configuration and picks the file.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <optional>

#include "hmpc/estimation/biped_state_estimator.hpp"
#include "hmpc/estimation/whole_body_ukf.hpp"
#include "hmpc/humanoid/closed_loop.hpp"
#include "hmpc/mpc/deadline_stop.hpp"
#include "hmpc/mpc/receding_horizon_mpc.hpp"

namespace hmpc::humanoid::detail {

using Clock = std::chrono::steady_clock;

template <int N, int A>
std::unique_ptr<RecedingHorizonMpc<HumanoidProblem<N, A>, N>> make_single_layer(
    const Motion& motion, const BasicState<A>& initial, ThreadPool* pool, ProblemConfig config,
    double step, int iteration_cap, double sampling_period) {
  config = model_config(motion, config);
  config.step = step;
  typename RecedingHorizonMpc<HumanoidProblem<N, A>, N>::Config mpc;
  mpc.solver = layer_solver(motion);
  if (iteration_cap > 0) mpc.solver.max_iterations = iteration_cap;
  mpc.steps_per_sample = static_cast<int>(std::lround(sampling_period / step));
  return std::make_unique<RecedingHorizonMpc<HumanoidProblem<N, A>, N>>(
      HumanoidProblem<N, A>(motion, initial, config, pool), mpc);
}

// What the loop needs from each MPC.
template <class Mpc>
auto& problem_of(Mpc& mpc) {
  return mpc.problem();
}
template <int A>
auto& problem_of(BasicCoarseFast<A>& mpc) {
  return mpc.upper_problem();
}
template <class Mpc>
int iterations_of(const Mpc& mpc) {
  return mpc.last_result().iterations;
}
template <int A>
int iterations_of(const BasicCoarseFast<A>& mpc) {
  return mpc.last_upper_result().iterations;
}
template <class Mpc>
int fast_iterations_of(const Mpc&) {
  return 0;
}
template <int A>
int fast_iterations_of(const BasicCoarseFast<A>& mpc) {
  return mpc.last_fast_result().iterations;
}
// Coarse-Fast's lower-layer correction in the period's applied inputs: the largest |nu| of
// Eq. 2.36 over its fine steps 0..steps-1 and the joints, as a fraction of the joint's torque
// limit; 0 for a single-layer MPC.
template <class Mpc, class Limit>
double lower_layer_change_of(const Mpc&, const Limit&, int) {
  return 0.0;
}
template <int A, class Limit>
double lower_layer_change_of(const BasicCoarseFast<A>& mpc, const Limit& limit, int steps) {
  double change = 0.0;
  for (int j = 0; j < steps; ++j) {
    change = std::max(
        change,
        (mpc.planned_control(j) - mpc.held_control(j)).cwiseAbs().cwiseQuotient(limit).maxCoeff());
  }
  return change;
}
template <class Mpc>
bool stopped_early(const Mpc& mpc) {
  return mpc.last_result().status == SolveStatus::kBudgetExhausted;
}
template <int A>
bool stopped_early(const BasicCoarseFast<A>& mpc) {
  return mpc.last_upper_result().status == SolveStatus::kBudgetExhausted ||
         mpc.last_fast_result().status == SolveStatus::kBudgetExhausted;
}

template <int A>
bool finite(const BasicState<A>& x) {
  return x.q.allFinite() && x.v.allFinite();
}

// Height above the ground of the lowest part other than the feet: head, torso origin (mid-hip),
// hip joints, knees (ClosedLoopConfig::fallen_clearance).
template <int A>
double lowest_non_foot_point(const BasicDynamics<A>& dynamics, const BasicState<A>& x) {
  using Model = BasicModel<A>;
  const Model& model = dynamics.model();
  BasicKinematics<A> kin;
  dynamics.kinematics(x.q, x.v, kin);
  double lowest =
      std::min(kin.position[0].z(), (kin.position[0] + kin.rotation[0] * model.vertex).z());
  for (int leg = 0; leg < 2; ++leg) {
    lowest = std::min({lowest, kin.position[Model::body_of(leg, kHipFlexion)].z(),
                       kin.position[Model::body_of(leg, kKnee)].z()});
  }
  return lowest;
}

// A time in seconds as a clock duration.
inline Clock::duration period(double seconds) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

// Coarse-Fast's upper layer's share of the period when truncating. Our choice. The upper layer
// does about three quarters of the work (motions IV-V untruncated, per update: upper 6
// iterations, 60 linearised and 244 simulated steps of 6 sub-steps; lower 5.5 iterations, 61
// and 171 steps of 2 sub-steps), and 2/3 left it 1.3 iterations on the loaded machine, where
// motion IV fell. Measured over shares, truncated warm runs of III, V, VI, VII and VIII, 12
// each, interleaved: 0.75 passed 35 of 60 physical checks (VIII 0 of 12: its first upper solve
// stopped one iteration short with 8 ms of the period unused) and overran 30 ms in 10
// samples; 0.8 passed 45, 10 samples; 0.85 passed 48, 6 samples; 0.9 (6 each) 26 of 30, 22
// samples; leaving the lower layer only two of its iterations' time, 25 of 30 and 29 samples.
// The price is margin on a loaded machine: with a busy process competing for the cores (all
// motions, warm and cold), 0.85 overran in 34 of 4740 samples, 0.75 in 24 of 4816.
constexpr double kUpperShare = 0.85;

// Each layer's iteration time, carried from one update to the next (deadline_stop.hpp); a
// single-layer MPC uses `upper`.
struct LayerTimes {
  IterationTime<Clock> upper, fast;
};

// One update within the sampling period, truncated (ClosedLoopConfig::truncate) by
// deadline_stop.hpp's rule. Coarse-Fast: the upper layer until kUpperShare of the period, the
// lower layer until its end.
template <class Mpc, int A>
void update(Mpc& mpc, const BasicState<A>& x, Clock::time_point start, double sampling_period,
            bool truncate, LayerTimes& times) {
  const Clock::time_point end = start + period(sampling_period);
  DeadlineStop<Clock> stop(end, end, times.upper, truncate);
  mpc.update(to_vector(x), stop);
}
template <int A>
void update(BasicCoarseFast<A>& mpc, const BasicState<A>& x, Clock::time_point start,
            double sampling_period, bool truncate, LayerTimes& times) {
  const Clock::time_point end = start + period(sampling_period);
  DeadlineStop<Clock> upper(start + period(kUpperShare * sampling_period), end, times.upper,
                            truncate);
  DeadlineStop<Clock> fast(end, end, times.fast, truncate);
  mpc.update(to_vector(x), upper, fast);
}

// Adds `weight` times the vertical contact forces of `contact` to the sample's left foot,
// right foot and seat.
template <int A>
void add_vertical_forces(const BasicContactState<A>& contact, double weight,
                         BasicClosedLoopSample<A>& sample) {
  for (int i = 0; i < contact.count; ++i) {
    const double fz = weight * contact.force[i].z();
    (i < kFootPoints   ? sample.left_force
     : i < kSolePoints ? sample.right_force
                       : sample.seat_force) += fz;
  }
}

// What the MPC is given (ClosedLoopConfig::feedback): the truth, or an estimator on the biped's
// simulated sensors, which read the plant every simulator step, or the true base with the
// sensors' joints.
template <int A>
class Feedback {
 public:
  // `contact` is the plant's (the motion's: with a chair for motion IV), which the estimators'
  // models share.
  Feedback(const ClosedLoopConfig& config, const BasicModel<A>& model,
           const ContactParameters& contact, const BasicState<A>& initial) {
    if constexpr (A == 0) {
      if (config.feedback == StateFeedback::kTruth) return;
      sensors_.emplace(model, config.sensors);
      if (config.feedback == StateFeedback::kInvariantEkf) {
        estimation::InvariantEkfConfig filter;
        filter.contact = contact;
        estimator_.emplace(config.problem.parameters, filter);
      } else if (config.feedback == StateFeedback::kWholeBodyUkf) {
        estimation::WholeBodyUkfConfig filter;
        filter.contact = contact;
        ukf_.emplace(config.problem.parameters, filter);
      }
      // The robot held still in its starting stance: nothing moves, gravity alone is felt.
      sensors_->start_at_rest(initial.q);
      const BasicVelocity<A> still = BasicVelocity<A>::Zero();
      const int samples = static_cast<int>(std::lround(config.rest_seconds / kSimulatorStep));
      estimation::ImuRest rest;
      for (int k = 0; k < samples; ++k) {
        reading_ = sensors_->measure(initial.q, still, still);
        if (estimator_) estimator_->rest(reading_, kSimulatorStep);
        rest.add(reading_.imu, kSimulatorStep);
      }
      if (estimator_) estimator_->start();
      if (ukf_) ukf_->initialize_at_rest(rest, reading_.angles);
    }
  }

  // One simulator step that ended at `x` after the mean acceleration `a` under torques `u`.
  void step(const BasicState<A>& x, const BasicVelocity<A>& a, const BasicJointVector<A>& u) {
    if constexpr (A == 0) {
      if (!sensors_) return;
      reading_ = sensors_->measure(x.q, x.v, a);
      if (estimator_) estimator_->update(reading_, kSimulatorStep);
      if (ukf_) ukf_->update(u, reading_, kSimulatorStep);
    }
  }

  // What the MPC solves from now, the plant being at `truth`.
  BasicState<A> state(const BasicState<A>& truth) const {
    if constexpr (A == 0) {
      if (estimator_) return estimator_->state();
      if (ukf_) return ukf_->state();
      if (sensors_) return with_sensed_joints(truth);
    }
    return truth;
  }

  // The same, with its spread and trust, into `sample`.
  void give(const BasicState<A>& truth, BasicClosedLoopSample<A>& sample) const {
    if constexpr (A == 0) {
      if (sensors_ && !estimator_ && !ukf_) {
        sample.feedback = with_sensed_joints(truth);
        return;
      }
      if (sensors_) {
        const estimation::BaseEstimate e =
            estimator_ ? estimator_->filter().estimate() : ukf_->estimate();
        sample.feedback = estimator_ ? estimator_->state(e) : ukf_->state();
        sample.spread = e.spread;
        sample.trust = e.trust;
        return;
      }
    }
    sample.feedback = truth;
  }

 private:
  // `truth`'s base with the last reading's joints.
  BasicState<A> with_sensed_joints(BasicState<A> truth) const {
    truth.q.template tail<kJoints>() = reading_.angles;
    truth.v.template tail<kJoints>() = reading_.rates;
    return truth;
  }

  std::optional<BipedSensors> sensors_;
  SensorReadings reading_;
  std::optional<estimation::BipedStateEstimator> estimator_;
  std::optional<estimation::WholeBodyUkf> ukf_;
};

template <class Mpc, int A>
BasicClosedLoopRun<A> simulate(Mpc& mpc, const Motion& motion, const ClosedLoopConfig& config,
                               const BasicState<A>& initial, double duration) {
  using State = BasicState<A>;
  ProblemConfig plant = config.problem;
  plant.contact = contact_for(motion, config.problem.contact);
  const BasicStateCost<A> observer(motion, initial, plant);
  const BasicModel<A> model(plant.parameters);
  const BasicDynamics<A> body(model);
  BasicStepMap<A> simulator(model, plant.parameters, plant.contact, kSimulatorStep);
  // The period's input steps (the lower layer's, Delta t_f each) and their simulator steps.
  const double sampling_period = config.timing.upper_step;
  const int fine_steps = config.timing.fine_steps_per_upper_step();
  const int simulator_steps =
      static_cast<int>(std::lround(config.timing.fast_step / kSimulatorStep));

  Feedback<A> feedback(config, model, plant.contact, initial);
  if (config.warm_start) mpc.initialize(to_vector(feedback.state(initial)), kOfflineIterations);
  BasicClosedLoopRun<A> run;
  run.initial = initial;
  run.feedback = config.feedback;
  run.sampling_period = sampling_period;
  const int count = static_cast<int>(std::lround(duration / sampling_period));
  run.samples.reserve(count);
  if (config.record_milliseconds) {
    run.milliseconds.reserve(static_cast<std::size_t>(count) * fine_steps * simulator_steps);
  }
  State x = initial;
  LayerTimes times;
  BasicJointVector<A> applied;  // the torque of the period's last fine step
  for (int k = 0; k < count; ++k) {
    const double t0 = k * sampling_period;
    BasicClosedLoopSample<A> sample;
    feedback.give(x, sample);
    if (sample.trust == estimation::Trust::kLost) {
      run.estimate_lost_at = t0;
      break;
    }
    problem_of(mpc).set_start_time(t0);
    if (k > 0) problem_of(mpc).set_applied_torque(applied);
    const auto start = Clock::now();
    update(mpc, sample.feedback, start, sampling_period, config.truncate, times);
    sample.solve_seconds = std::chrono::duration<double>(Clock::now() - start).count();
    sample.work = mpc.last_work();
    sample.truncated = stopped_early(mpc);
    sample.torque = mpc.planned_control(0);
    applied = mpc.planned_control(fine_steps - 1);
    for (int j = 0; j < fine_steps; ++j) {
      const BasicJointVector<A> u = mpc.planned_control(j);
      for (int i = 0; i < simulator_steps; ++i) {
        const double t = t0 + (j * simulator_steps + i) * kSimulatorStep;
        sample.cost += (observer.value(to_vector(x), t) + observer.control_cost(u)) *
                       (kSimulatorStep / kCoarseStep);
        const State next = simulator.step(x, u, kSimulatorStep);
        const BasicVelocity<A> acceleration = (next.v - x.v) / kSimulatorStep;
        if (config.record_milliseconds) {
          run.milliseconds.push_back({t + kSimulatorStep, next, acceleration, u});
        }
        feedback.step(next, acceleration, u);
        x = next;
        add_vertical_forces(simulator.contact_state(), 1.0 / (fine_steps * simulator_steps),
                            sample);
      }
    }
    sample.time = t0 + sampling_period;
    sample.state = x;
    sample.iterations = iterations_of(mpc);
    sample.fast_iterations = fast_iterations_of(mpc);
    sample.lower_layer_change = lower_layer_change_of(mpc, model.torque_limit, fine_steps);
    sample.plan_usable = mpc.last_plan_usable();
    if (finite(x)) sample.base = observer.features(x);
    run.samples.push_back(sample);
    if (!finite(x) || lowest_non_foot_point(body, x) < config.fallen_clearance) {
      run.fell_at = sample.time;
      break;
    }
  }
  return run;
}

// The run of each MPC kind from `initial` (closed_loop_<kind>.cpp); `pool` may be null.
template <int A>
BasicClosedLoopRun<A> run_fine(const Motion& motion, const ClosedLoopConfig& config,
                               const BasicState<A>& initial, ThreadPool* pool, double duration);
template <int A>
BasicClosedLoopRun<A> run_coarse(const Motion& motion, const ClosedLoopConfig& config,
                                 const BasicState<A>& initial, ThreadPool* pool, double duration);
template <int A>
BasicClosedLoopRun<A> run_coarse_fast(const Motion& motion, const ClosedLoopConfig& config,
                                      const BasicState<A>& initial, ThreadPool* pool,
                                      double duration);

}  // namespace hmpc::humanoid::detail
