// Inverse optimal control (Ch. 4): L-BFGS, the local IOC likelihood's gradient against
// finite differences, bad demonstrations and weights, the file formats. Learning from the
// robot's own MPC: ioc_learning_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>

#include "hmpc/ioc/files.hpp"
#include "hmpc/ioc/learn.hpp"
#include "ioc_test_support.hpp"

namespace hmpc::ioc {
namespace {

using humanoid::Motion;

using test::jump_motion;
using test::own_demonstration;

TEST(Lbfgs, MinimisesTheRosenbrockFunction) {
  const Objective rosenbrock = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g.resize(2);
    g[0] = -2.0 * (1.0 - x[0]) - 400.0 * x[0] * (x[1] - x[0] * x[0]);
    g[1] = 200.0 * (x[1] - x[0] * x[0]);
    return (1.0 - x[0]) * (1.0 - x[0]) + 100.0 * std::pow(x[1] - x[0] * x[0], 2);
  };
  LbfgsConfig config;
  config.max_iterations = 200;
  config.gradient_tolerance = 1e-10;
  const LbfgsResult result = minimize_lbfgs(rosenbrock, Eigen::Vector2d(-1.2, 1.0), config);
  EXPECT_TRUE(result.converged) << result.stop;
  EXPECT_NEAR(result.x[0], 1.0, 1e-6);
  EXPECT_NEAR(result.x[1], 1.0, 1e-6);
}

TEST(Lbfgs, RejectsANonFiniteStart) {
  const Objective bad = [](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
    g = x;
    return std::nan("");
  };
  EXPECT_THROW(minimize_lbfgs(bad, Eigen::Vector2d(1.0, 1.0), LbfgsConfig{}),
               std::invalid_argument);
}

// Both of LocalIoc's terms: the likelihood (Eq. 4.10) and the excess cost.
class LocalIocTerm : public ::testing::TestWithParam<bool> {};

TEST_P(LocalIocTerm, GradientMatchesFiniteDifferences) {
  const bool likelihood = GetParam();
  const Motion motion = jump_motion();
  // The crouch before the jump: two windows. (Across a landing the step map's Jacobians reach
  // 1e4 and the likelihood carries round-off of 1e-5, too much for difference quotients.)
  const std::vector<Demonstration> demos{own_demonstration(motion, 0.6, Eigen::Vector3d::Zero())};
  const LocalIoc ioc(motion, demos);
  ASSERT_EQ(ioc.window_count(), 2);
  const auto term = [&](const Weights& w, Weights* gradient = nullptr) {
    return likelihood ? ioc.log_likelihood(w, gradient) : ioc.excess_cost(w, gradient);
  };
  // Weights of mixed magnitude, like a learned set; the derivative in log w (what the learner
  // uses), so that every entry is on the same scale.
  Weights w = weights_of(motion.weights);
  w[kBeta] *= 0.3;
  w[kVy] *= 3.0;
  Weights gradient;
  term(w, &gradient);
  // Central differences in log w_k at steps h and h/2 combined by Richardson extrapolation,
  // (4 D(h/2) - D(h)) / 3, which cancels the h^2 error term. Tolerance 5e-4 relative: on
  // aarch64 (qemu) the differences of w_q1 stay 1.2e-4 to 1.7e-4 off with or without extrapolation,
  // the likelihood's own round-off there; gradient bugs met while writing this were 10 % off or
  // more.
  const auto difference = [&](int k, double h) {
    Weights plus = w, minus = w;
    plus[k] *= std::exp(h);
    minus[k] *= std::exp(-h);
    return (term(plus) - term(minus)) / (2.0 * h);
  };
  for (int k = 0; k < kWeightCount; ++k) {
    const double h = 2e-3;
    const double numeric = (4.0 * difference(k, h / 2) - difference(k, h)) / 3.0;
    const double analytic = w[k] * gradient[k];
    EXPECT_NEAR(analytic, numeric, 5e-4 * std::max(1.0, std::abs(numeric))) << kWeightNames[k];
  }
}

INSTANTIATE_TEST_SUITE_P(LogLikelihoodAndExcessCost, LocalIocTerm, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "LogLikelihood" : "ExcessCost";
                         });

TEST(LocalIoc, RejectsBadDemonstrationsAndWeights) {
  const Motion motion = jump_motion();
  Demonstration demo;
  demo.states.assign(12, humanoid::StateVector::Zero());
  demo.inputs.assign(12, humanoid::JointVector::Zero());
  EXPECT_THROW(LocalIoc(motion, {demo}), std::invalid_argument);  // counts do not match
  demo.states.push_back(humanoid::StateVector::Zero());
  demo.states[5][9] = std::nan("");
  EXPECT_THROW(LocalIoc(motion, {demo}), std::invalid_argument);
  const LocalIoc none(motion, {});
  EXPECT_EQ(none.window_count(), 0);
  EXPECT_THROW(learn_weights(none), std::invalid_argument);
}

// A file's text must be rejected with a message containing `what`.
template <class Parse>
void expect_rejected(const Parse& parse, const std::string& text, const std::string& what) {
  std::istringstream in(text);
  try {
    parse(in, "test.file");
    ADD_FAILURE() << "accepted:\n" << text;
  } catch (const IocFileError& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(IocFiles, WeightsRoundTripAndBadFilesAreRejected) {
  Weights w = initial_weights();
  w[kHeight] = 1.0 / 3.0;
  std::stringstream file;
  write_weights(file, w, "learned from 2 demonstrations\nlog p -12.5");
  EXPECT_EQ(parse_weights(file, "round trip"), w);  // 17 digits: exact
  std::ostringstream good;
  write_weights(good, w);
  const std::string text = good.str();
  const auto parse = [](std::istream& in, const std::string& source) {
    return parse_weights(in, source);
  };
  expect_rejected(parse, "", "no version line");
  expect_rejected(parse, "hmpc-ioc-weights 2\n", "version line");
  const std::string height = "w_height = 0.33333333333333331\n";
  ASSERT_NE(text.find(height), std::string::npos);
  const auto with = [&](const std::string& line) {
    std::string t = text;
    return t.replace(t.find(height), height.size(), line);
  };
  expect_rejected(parse, with(""), "missing w_height");
  expect_rejected(parse, with(height + height), "w_height given twice");
  expect_rejected(parse, with("w_height = -1\n"), "must be > 0");
  expect_rejected(parse, with("w_height = 0\n"), "must be > 0");
  expect_rejected(parse, with("w_height = nan\n"), "not a finite number");
  expect_rejected(parse, with("w_height = 1e400\n"), "not a finite number");
  expect_rejected(parse, with("w_height = 2 m\n"), "not a finite number");
  expect_rejected(parse, with("w_height 2\n"), "key = value");
  expect_rejected(parse, with("w_q4 = 1\n"), "unknown weight 'w_q4'");
}

TEST(IocFiles, DemonstrationsRoundTripAndBadFilesAreRejected) {
  Demonstration a, b;
  a.start_time = 0.0;
  b.start_time = 0.45;
  humanoid::StateVector x = humanoid::StateVector::Zero();
  x[3] = 1.0;
  for (int k = 0; k < 3; ++k) {
    x[0] = 0.1 * k;
    a.states.push_back(x);
    b.states.push_back(x);
    if (k < 2) {
      a.inputs.push_back(humanoid::JointVector::Constant(k + 0.5));
      b.inputs.push_back(humanoid::JointVector::Constant(-k - 1.0 / 3.0));
    }
  }
  b.states.pop_back();
  b.inputs.pop_back();
  std::stringstream file;
  write_demonstrations(file, {a, b});
  const std::string text = file.str();
  const std::vector<Demonstration> read = parse_demonstrations(file, "round trip");
  ASSERT_EQ(read.size(), 2u);
  EXPECT_EQ(read[1].start_time, 0.45);
  EXPECT_EQ(read[0].states, a.states);
  EXPECT_EQ(read[0].inputs, a.inputs);
  EXPECT_EQ(read[1].inputs, b.inputs);

  const auto parse = [](std::istream& in, const std::string& source) {
    return parse_demonstrations(in, source);
  };
  std::vector<std::string> lines;
  std::istringstream split(text);
  for (std::string line; std::getline(split, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 2u + 3u + 2u);
  const auto join = [](const std::vector<std::string>& ls) {
    std::string t;
    for (const auto& l : ls) t += l + "\n";
    return t;
  };
  // Replaces field `column` of line `index`.
  const auto edit = [&](int index, int column, const std::string& value) {
    std::vector<std::string> ls = lines;
    std::vector<std::string> fields;
    std::istringstream row(ls[index]);
    for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
    while (fields.size() < 39) fields.emplace_back();
    fields[column] = value;
    std::string joined;
    for (std::size_t i = 0; i < fields.size(); ++i) joined += (i ? "," : "") + fields[i];
    ls[index] = joined;
    return join(ls);
  };
  expect_rejected(parse, "hmpc-ioc-demonstrations 2\n", "version line");
  expect_rejected(parse, lines[0] + "\ndemo,time\n", "header");
  expect_rejected(parse, join({lines[0], lines[1]}), "no demonstration");
  expect_rejected(parse, edit(2, 5, "nan"), "x3: not a finite number");
  expect_rejected(parse, edit(2, 5, "0.9"), "quaternion is not of unit norm");
  expect_rejected(parse, edit(3, 31, "1e999"), "u0: not a finite number");
  expect_rejected(parse, edit(3, 1, "0.04"), "0.03 s apart");
  expect_rejected(parse, edit(5, 0, "3"), "out of order");
  expect_rejected(parse, edit(3, 32, ""), "u1: not a finite number");
  expect_rejected(parse, edit(4, 35, "1"), "all eight or none");
  expect_rejected(parse, join({lines[0], lines[1], lines[2]}), "ends inside a demonstration");
  expect_rejected(parse, join({lines[0], lines[1], lines[4]}), "at least one input");
  expect_rejected(parse, join({lines[0], lines[1], lines[2], lines[3], lines[4], lines[4]}),
                  "after the demonstration's last row");
  expect_rejected(parse, join({lines[0], lines[1], lines[2], lines[5]}), "last row has inputs");
  std::string short_row = lines[2].substr(0, lines[2].rfind(','));
  expect_rejected(parse, join({lines[0], lines[1], short_row}), "expected 39 fields");
}

}  // namespace
}  // namespace hmpc::ioc
