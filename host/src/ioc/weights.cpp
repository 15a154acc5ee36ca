#include "hmpc/ioc/weights.hpp"

namespace hmpc::ioc {

const std::array<const char*, kWeightCount> kWeightNames = {
    "w_HAA", "w_HFE", "w_KFE", "w_AFE", "w_alpha", "w_beta", "w_height",
    "w_q1",  "w_q2",  "w_q3",  "w_vx",  "w_vy",    "w_vz"};

Weights weights_of(const humanoid::CostWeights& weights) {
  Weights w;
  for (int j = 0; j < kControlWeights; ++j) w[kHAA + j] = weights.control[j];
  w[kAlpha] = weights.alpha;
  w[kBeta] = weights.beta;
  w[kHeight] = weights.height;
  w.segment<3>(kQ1) = weights.attitude.head<3>();
  w.segment<3>(kVx) = weights.velocity;
  return w;
}

humanoid::CostWeights with_weights(humanoid::CostWeights base, const Weights& w) {
  for (int j = 0; j < kControlWeights; ++j) base.control[j] = w[kHAA + j];
  base.alpha = w[kAlpha];
  base.beta = w[kBeta];
  base.height = w[kHeight];
  base.attitude.head<3>() = w.segment<3>(kQ1);
  base.velocity = w.segment<3>(kVx);
  return base;
}

Weights initial_weights() {
  Weights w = Weights::Constant(1.0);
  w.head<kControlWeights>().setConstant(0.001);
  return w;
}

double cosine_similarity(const Weights& a, const Weights& b) {
  return a.dot(b) / (a.norm() * b.norm());
}

Weights log_errors_up_to_scale(const Weights& learned, const Weights& truth,
                               const std::array<bool, kWeightCount>& counted) {
  const Weights log_ratio = (learned.array() / truth.array()).log().matrix();
  double sum = 0.0;
  int count = 0;
  for (int k = 0; k < kWeightCount; ++k) {
    if (!counted[k]) continue;
    sum += log_ratio[k];
    ++count;
  }
  return (log_ratio.array() - (count > 0 ? sum / count : 0.0)).matrix();
}

}  // namespace hmpc::ioc
