#include "hmpc/dds/cost_weights.hpp"

#include "hmpc/dds/endpoint.hpp"

namespace hmpc::dds {

CostWeightsSample::CostWeightsSample(std::vector<std::pair<std::string, double>> weights)
    : weights_(std::move(weights)) {
  for (const auto& [name, value] : weights_) {
    names_.push_back(name.c_str());
    values_.push_back(value);
  }
  message_.header.stamp = from_seconds<msg::Time>(unix_time_s());
  message_.header.frame_id = borrow("");
  message_.names = borrow(names_.data(), names_.size());
  message_.values = borrow(values_.data(), values_.size());
}

bool publish_cost_weights(std::uint32_t domain_id, const std::string& config,
                          const std::string& ros_name,
                          std::vector<std::pair<std::string, double>> weights, double timeout_s,
                          std::string& error) {
  const Participant participant(domain_id, config);
  const Writer<msg::CostWeights> writer(participant, ros_name, Qos::state());
  if (!writer.wait_for_reader(timeout_s)) {
    error = "no reader subscribed to " + ros_name + " on domain " + std::to_string(domain_id) +
            " within " + std::to_string(timeout_s) + " s";
    return false;
  }
  const CostWeightsSample sample(std::move(weights));
  if (!writer.write(sample.message()) || !writer.wait_for_acks(timeout_s)) {
    error = "the weights on " + ros_name + " were not acknowledged within " +
            std::to_string(timeout_s) + " s";
    return false;
  }
  return true;
}

}  // namespace hmpc::dds
