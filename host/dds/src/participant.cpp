#include "hmpc/dds/participant.hpp"

#include <cctype>
#include <chrono>
#include <map>
#include <mutex>
#include <stdexcept>

#include "hmpc/dds/messages.hpp"

namespace hmpc::dds {

namespace {

// Cyclone runs one domain instance per domain id and process. A domain created with a
// configuration (dds_create_domain) lives until its handle is deleted, which also deletes
// every participant in it: count the users, delete it with the last one.
class DomainRegistry {
 public:
  static DomainRegistry& instance() {
    static DomainRegistry registry;
    return registry;
  }

  void acquire(std::uint32_t domain_id, const std::string& config) {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto found = domains_.find(domain_id);
    if (found != domains_.end()) {
      if (!config.empty() && config != found->second.config) {
        throw std::runtime_error("DDS domain " + std::to_string(domain_id) +
                                 " is already in use in this process with another configuration");
      }
      ++found->second.users;
      return;
    }
    if (config.empty()) return;  // Cyclone's implicit domain, counted by Cyclone itself
    const dds_entity_t handle = dds_create_domain(domain_id, config.c_str());
    if (handle == DDS_RETCODE_PRECONDITION_NOT_MET) {
      throw std::runtime_error("DDS domain " + std::to_string(domain_id) +
                               " is already in use in this process without the configuration");
    }
    if (handle < 0) {
      throw std::runtime_error("cannot create DDS domain " + std::to_string(domain_id) +
                               " with the given configuration (" + dds_strretcode(handle) +
                               "); Cyclone's message on stderr says why");
    }
    domains_.emplace(domain_id, Domain{handle, config, 1});
  }

  void release(std::uint32_t domain_id) {
    const std::lock_guard<std::mutex> lock(mutex_);
    auto found = domains_.find(domain_id);
    if (found == domains_.end() || --found->second.users > 0) return;
    dds_delete(found->second.handle);
    domains_.erase(found);
  }

 private:
  struct Domain {
    dds_entity_t handle;
    std::string config;
    int users;
  };
  std::mutex mutex_;
  std::map<std::uint32_t, Domain> domains_;
};

// rmw_qos_profile_sensor_data and rmw_qos_profile_default keep the last 5 and 10 samples.
constexpr std::int32_t kSensorDataDepth = 5;
constexpr std::int32_t kDefaultDepth = 10;
// ROS 2's default max_blocking_time of a reliable writer.
constexpr dds_duration_t kMaxBlocking = DDS_MSECS(100);

class QosHandle {
 public:
  explicit QosHandle(const Qos& qos) : qos_(dds_create_qos()) {
    // XCDR1, little-endian on our machines, as ROS 2's rmw_cyclonedds writes; the types are
    // @final, whose XCDR1 encoding is the plain CDR ROS 2 readers expect.
    const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
    dds_qset_data_representation(qos_, 1, &xcdr1);
    dds_qset_durability(qos_, DDS_DURABILITY_VOLATILE);
    switch (qos.profile) {
      case QosProfile::kSensorData:
        dds_qset_reliability(qos_, DDS_RELIABILITY_BEST_EFFORT, 0);
        dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, kSensorDataDepth);
        break;
      case QosProfile::kDefault:
        dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, kMaxBlocking);
        dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, kDefaultDepth);
        break;
      case QosProfile::kCommand:
        if (!(qos.deadline_s > 0) || !(qos.lease_s > 0)) {
          throw std::invalid_argument("a command QoS needs a positive deadline and lease");
        }
        dds_qset_reliability(qos_, DDS_RELIABILITY_RELIABLE, kMaxBlocking);
        dds_qset_history(qos_, DDS_HISTORY_KEEP_LAST, kDefaultDepth);
        dds_qset_deadline(qos_, to_duration(qos.deadline_s));
        dds_qset_liveliness(qos_, DDS_LIVELINESS_AUTOMATIC, to_duration(qos.lease_s));
        break;
    }
  }
  ~QosHandle() { dds_delete_qos(qos_); }
  QosHandle(const QosHandle&) = delete;
  QosHandle& operator=(const QosHandle&) = delete;
  const dds_qos_t* get() const { return qos_; }

 private:
  dds_qos_t* qos_;
};

bool valid_token(const std::string& name, std::size_t begin, std::size_t end) {
  if (begin == end || std::isdigit(static_cast<unsigned char>(name[begin]))) return false;
  for (std::size_t i = begin; i < end; ++i) {
    const auto c = static_cast<unsigned char>(name[i]);
    if (!std::isalnum(c) && c != '_') return false;
  }
  return true;
}

}  // namespace

dds_entity_t checked(dds_entity_t entity, const std::string& what) {
  if (entity < 0) {
    throw std::runtime_error("cannot create " + what + ": " + dds_strretcode(entity));
  }
  return entity;
}

dds_duration_t to_duration(double seconds) {
  // A week is "forever" here, and stays far inside dds_duration_t.
  constexpr double kLongest = 7 * 86400.0;
  if (!(seconds > 0)) return 0;
  return static_cast<dds_duration_t>(1e9 * (seconds < kLongest ? seconds : kLongest));
}

double unix_time_s() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

std::string dds_topic_name(const std::string& ros_name) {
  bool ok = ros_name.size() > 1 && ros_name[0] == '/';
  for (std::size_t begin = 1; ok && begin <= ros_name.size();) {
    std::size_t end = ros_name.find('/', begin);
    if (end == std::string::npos) end = ros_name.size();
    ok = valid_token(ros_name, begin, end);
    begin = end + 1;
  }
  if (!ok) {
    throw std::invalid_argument("'" + ros_name +
                                "' is not an absolute ROS 2 topic name (/token/token..., tokens of "
                                "letters, digits and '_', not starting with a digit)");
  }
  return "rt" + ros_name;
}

std::string loopback_config() {
  // ParticipantIndex auto gives each process a unicast discovery port of its own; Peers
  // 127.0.0.1 makes discovery probe the ports of indices 0..MaxAutoParticipantIndex there,
  // which is what replaces multicast discovery. 20 processes per domain is plenty for a
  // host controller, a few operators and tests.
  return "<CycloneDDS><Domain id=\"any\">"
         "<General><Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast></General>"
         "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>"
         "<Peers><Peer address=\"127.0.0.1\"/></Peers></Discovery>"
         "</Domain></CycloneDDS>";
}

Participant::Participant(std::uint32_t domain_id, const std::string& config)
    : domain_id_(domain_id) {
  DomainRegistry::instance().acquire(domain_id, config);
  handle_ = dds_create_participant(domain_id, nullptr, nullptr);
  if (handle_ < 0) {
    DomainRegistry::instance().release(domain_id);
    throw std::runtime_error("cannot create a DDS participant on domain " +
                             std::to_string(domain_id) + ": " + dds_strretcode(handle_));
  }
}

Participant::~Participant() {
  dds_delete(handle_);
  DomainRegistry::instance().release(domain_id_);
}

dds_entity_t Participant::topic(const dds_topic_descriptor_t& type,
                                const std::string& ros_name) const {
  const std::string name = dds_topic_name(ros_name);
  return checked(dds_create_topic(handle_, &type, name.c_str(), nullptr, nullptr),
                 "DDS topic " + name + " of type " + type.m_typename);
}

dds_entity_t Participant::writer(dds_entity_t topic, const Qos& qos) const {
  const QosHandle q(qos);
  return checked(dds_create_writer(handle_, topic, q.get(), nullptr), "a DDS writer");
}

dds_entity_t Participant::reader(dds_entity_t topic, const Qos& qos) const {
  const QosHandle q(qos);
  return checked(dds_create_reader(handle_, topic, q.get(), nullptr), "a DDS reader");
}

}  // namespace hmpc::dds
