// Named cost weights as hmpc_msgs/CostWeights, for whoever sends them: an operator's client,
// the IOC that learned them.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "hmpc/dds/messages.hpp"

namespace hmpc::dds {

// Where the humanoid's controller takes the 13 weights of the IOC (Eq. 4.31) by their motion-
// file names.
inline constexpr const char* kHumanoidCostWeightsTopic = "/hmpc/humanoid/cost_weights";

// A CostWeights sample over its own copy of the names and values, stamped now.
class CostWeightsSample {
 public:
  explicit CostWeightsSample(std::vector<std::pair<std::string, double>> weights);
  CostWeightsSample(const CostWeightsSample&) = delete;
  CostWeightsSample& operator=(const CostWeightsSample&) = delete;
  const msg::CostWeights& message() const { return message_; }

 private:
  std::vector<std::pair<std::string, double>> weights_;
  std::vector<const char*> names_;
  std::vector<double> values_;
  msg::CostWeights message_{};
};

// Publishes the weights once on ros_name (state QoS) as soon as a reader has matched, and waits
// for its acknowledgement. False, with the reason in `error`, when no reader matched or none
// acknowledged within timeout_s. `config` as for Participant.
bool publish_cost_weights(std::uint32_t domain_id, const std::string& config,
                          const std::string& ros_name,
                          std::vector<std::pair<std::string, double>> weights, double timeout_s,
                          std::string& error);

}  // namespace hmpc::dds
