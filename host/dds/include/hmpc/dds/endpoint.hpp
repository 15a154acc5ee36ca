// Typed writers and readers of one ROS 2 topic each, over a Participant.
#pragma once

#include <dds/dds.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>

#include "hmpc/dds/messages.hpp"
#include "hmpc/dds/participant.hpp"

namespace hmpc::dds {

template <class Message>
class Writer {
 public:
  Writer(const Participant& participant, const std::string& ros_name, const Qos& qos)
      : name_(ros_name),
        handle_(participant.writer(participant.topic(descriptor<Message>(), ros_name), qos)) {}

  // False if DDS refused the sample.
  bool write(const Message& message) const {
    return dds_write(handle_, &message) == DDS_RETCODE_OK;
  }

  // Readers matched so far (discovered, QoS compatible).
  std::uint32_t matched_readers() const {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(handle_, &status) == DDS_RETCODE_OK
               ? status.current_count
               : 0;
  }
  // Waits until a reader has matched; false on timeout.
  bool wait_for_reader(double timeout_s) const {
    const dds_time_t end = dds_time() + to_duration(timeout_s);
    while (matched_readers() == 0) {
      if (dds_time() >= end) return false;
      dds_sleepfor(DDS_MSECS(10));
    }
    return true;
  }
  // Waits until every matched reliable reader acknowledged what was written; false on timeout.
  bool wait_for_acks(double timeout_s) const {
    return dds_wait_for_acks(handle_, to_duration(timeout_s)) == DDS_RETCODE_OK;
  }

  const std::string& ros_name() const { return name_; }
  dds_entity_t handle() const { return handle_; }

 private:
  std::string name_;
  dds_entity_t handle_;
};

template <class Message>
class Reader {
 public:
  Reader(const Participant& participant, const std::string& ros_name, const Qos& qos)
      : name_(ros_name),
        handle_(participant.reader(participant.topic(descriptor<Message>(), ros_name), qos)),
        waitset_(checked(dds_create_waitset(participant.handle()), "a DDS waitset")) {
    const dds_entity_t condition = checked(dds_create_readcondition(handle_, DDS_ANY_STATE),
                                           "a DDS read condition on " + ros_name);
    checked(dds_waitset_attach(waitset_, condition, 0), "a DDS waitset attachment");
  }

  // Takes every pending sample, calling visit(const Message&) or, if it takes them,
  // visit(const Message&, const dds_sample_info_t&) on each that carries data (the others
  // announce a writer's departure), in arrival order. The message lives in memory DDS lends
  // until visit returns. Returns how many were visited.
  template <class Visit>
  std::size_t take(Visit&& visit) const {
    std::size_t visited = 0;
    for (;;) {
      Loan loan{handle_};
      const dds_return_t n =
          dds_take(handle_, loan.buffers.data(), loan.infos.data(), kBatch, kBatch);
      if (n <= 0) return visited;
      loan.count = n;
      for (dds_return_t i = 0; i < n; ++i) {
        if (!loan.infos[i].valid_data) continue;
        ++visited;
        const auto& message = *static_cast<const Message*>(loan.buffers[i]);
        if constexpr (std::is_invocable_v<Visit, const Message&, const dds_sample_info_t&>) {
          visit(message, loan.infos[i]);
        } else {
          visit(message);
        }
      }
      if (static_cast<std::size_t>(n) < kBatch) return visited;
    }
  }

  // Waits until a sample is pending; false on timeout.
  bool wait(double timeout_s) const {
    return dds_waitset_wait(waitset_, nullptr, 0, to_duration(timeout_s)) > 0;
  }

  // kCommand readers: how often a deadline passed without a sample, since creation.
  std::uint32_t deadline_misses() const {
    dds_requested_deadline_missed_status_t status{};
    return dds_get_requested_deadline_missed_status(handle_, &status) == DDS_RETCODE_OK
               ? status.total_count
               : 0;
  }
  // Whether this writer (a sample's publication_handle) is still matched: false once it was
  // deleted or its participant left.
  bool matched(dds_instance_handle_t writer) const {
    constexpr std::size_t kMost = 64;
    std::array<dds_instance_handle_t, kMost> writers{};
    const dds_return_t n = dds_get_matched_publications(handle_, writers.data(), kMost);
    for (dds_return_t i = 0; i < n && i < dds_return_t(kMost); ++i) {
      if (writers[std::size_t(i)] == writer) return true;
    }
    return false;
  }
  std::uint32_t matched_writers() const {
    dds_subscription_matched_status_t status{};
    return dds_get_subscription_matched_status(handle_, &status) == DDS_RETCODE_OK
               ? status.current_count
               : 0;
  }

  const std::string& ros_name() const { return name_; }
  dds_entity_t handle() const { return handle_; }

 private:
  static constexpr std::size_t kBatch = 16;

  // Samples DDS lent to a take, returned however the visit ends.
  struct Loan {
    explicit Loan(dds_entity_t r) : reader(r) {}
    ~Loan() {
      if (count > 0) dds_return_loan(reader, buffers.data(), count);
    }
    Loan(const Loan&) = delete;
    Loan& operator=(const Loan&) = delete;
    dds_entity_t reader;
    std::array<void*, kBatch> buffers{};  // buffers[0] null: DDS lends its own memory
    std::array<dds_sample_info_t, kBatch> infos{};
    dds_return_t count = 0;
  };

  std::string name_;
  dds_entity_t handle_;
  dds_entity_t waitset_;
};

}  // namespace hmpc::dds
