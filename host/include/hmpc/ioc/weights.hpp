// The cost weights inverse optimal control estimates (thesis Sec. 4.3.1, Eqs. 4.31-4.35):
//   w = {w_HAA, w_HFE, w_KFE, w_AFE,  w_alpha, w_beta, w_height,  w_q1, w_q2, w_q3,  w_vx, w_vy,
//   w_vz}
// The cost is linear in them (Eq. 4.3). The motion's other weights are not estimated and stay
// as its file has them: w_q4 and the angular-velocity weights (the thesis fixes them at 0),
// the foot-height weight (ours, motion.hpp) and the lower layer's.
#pragma once

#include <array>

#include "hmpc/humanoid/motion.hpp"

namespace hmpc::ioc {

constexpr int kWeightCount = 13;
using Weights = Eigen::Matrix<double, kWeightCount, 1>;

// Positions in Eq. 4.31's order.
enum WeightIndex { kHAA, kHFE, kKFE, kAFE, kAlpha, kBeta, kHeight, kQ1, kQ2, kQ3, kVx, kVy, kVz };
constexpr int kControlWeights = 4;  // w_1..w_4, Eq. 4.32

// The motion-file keys (motion.hpp) of the weights, in Eq. 4.31's order.
extern const std::array<const char*, kWeightCount> kWeightNames;

Weights weights_of(const humanoid::CostWeights& weights);
// `base` with the 13 weights replaced by `w`.
humanoid::CostWeights with_weights(humanoid::CostWeights base, const Weights& w);
// Sec. 4.3.1: "The weight parameters for the state- and control-costs were initialized with
// the values of 1.0 and 0.001".
Weights initial_weights();
// a.b / (|a| |b|): agreement up to scale.
double cosine_similarity(const Weights& a, const Weights& b);
// log(learned_k / true_k) after one common scale, the mean of the log ratios over the weights
// `counted` marks (IOC recovers weights up to scale): 0 where a weight was recovered exactly.
Weights log_errors_up_to_scale(const Weights& learned, const Weights& truth,
                               const std::array<bool, kWeightCount>& counted);

}  // namespace hmpc::ioc
