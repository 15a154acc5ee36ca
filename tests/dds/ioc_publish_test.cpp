// hmpc-ioc learn --publish-domain: the weights it learned reach a DDS reader of the humanoid's
// cost-weights topic as hmpc_msgs/CostWeights, named as in the weights file and equal to it;
// with no reader it says so and fails, after writing the file.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "hmpc/dds/cost_weights.hpp"
#include "hmpc/dds/endpoint.hpp"
#include "hmpc/dds/validation.hpp"
#include "hmpc/ioc/files.hpp"
#include "hmpc/ioc/weights.hpp"
#include "hmpc/platform/linux/child_process.hpp"

namespace {

namespace dds = hmpc::dds;
using hmpc::platform::Child;

constexpr std::uint32_t kDomain = 105;  // no other test uses it
constexpr double kPatience_s = 120;

// A directory of the case's own (ctest runs the cases in parallel), empty.
std::string fresh_dir(const std::string& name) {
  const char* tmp = std::getenv("TMPDIR");
  const std::string dir = std::string(tmp ? tmp : "/tmp") + "/hmpc-ioc-publish-test-" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Runs hmpc-ioc; its exit status, its output in `output`.
int ioc(const std::vector<std::string>& args, const std::string& log, std::string& output) {
  Child child;
  std::string error;
  if (!child.start(HMPC_IOC_PROGRAM, args, log, error)) {
    output = error;
    return -1;
  }
  const int status = child.wait(kPatience_s);
  output = child.output() + child.errors();
  return status;
}

// One short standing run's demonstration, then learning from it that publishes on `domain`.
int demos_then_learn(const std::string& dir, std::uint32_t domain, std::string& output) {
  const int demos = ioc({"demos", "--motion", "I-standing", "--duration", "0.3", "--count", "1",
                         "--from", "runs", "--out", dir + "/demos.csv"},
                        dir + "/demos.out", output);
  if (demos != 0) return demos;
  return ioc({"learn", "--motion", "I-standing", "--demos", dir + "/demos.csv", "--iterations", "3",
              "--out", dir + "/learned.weights", "--publish-domain", std::to_string(domain),
              "--dds-loopback", "--publish-timeout", "5"},
             dir + "/learn.out", output);
}

TEST(IocPublish, LearnedWeightsReachAReaderAsCostWeights) {
  const std::string dir = fresh_dir("read");
  const dds::Participant participant(kDomain, dds::loopback_config());
  const dds::Reader<dds::msg::CostWeights> reader(participant, dds::kHumanoidCostWeightsTopic,
                                                  dds::Qos::state());
  std::string output;
  ASSERT_EQ(demos_then_learn(dir, kDomain, output), 0) << output;
  EXPECT_NE(output.find("published the weights on /hmpc/humanoid/cost_weights"), std::string::npos)
      << output;

  const hmpc::ioc::Weights learned = hmpc::ioc::load_weights(dir + "/learned.weights");
  std::vector<dds::NamedRange> known;
  for (const char* name : hmpc::ioc::kWeightNames) known.push_back({name, 1e-300, 1e300});
  int received = 0;
  ASSERT_TRUE(reader.wait(kPatience_s));
  reader.take([&](const dds::msg::CostWeights& w) {
    ++received;
    const dds::Verdict v = dds::validate(w, known.data(), known.size(), dds::unix_time_s(), {});
    EXPECT_TRUE(v.ok) << v.detail;
    ASSERT_EQ(w.names._length, std::uint32_t(hmpc::ioc::kWeightCount));
    for (int k = 0; k < hmpc::ioc::kWeightCount; ++k) {
      EXPECT_STREQ(w.names._buffer[k], hmpc::ioc::kWeightNames[std::size_t(k)]);
      EXPECT_EQ(w.values._buffer[k], learned[k])
          << hmpc::ioc::kWeightNames[std::size_t(k)] << ": the file keeps all 17 digits";
    }
  });
  EXPECT_EQ(received, 1);
}

TEST(IocPublish, NoReaderIsAnErrorAfterTheFileIsWritten) {
  const std::string dir = fresh_dir("unread");
  std::string output;
  EXPECT_EQ(demos_then_learn(dir, kDomain + 1, output), 1) << output;
  EXPECT_NE(output.find("no reader subscribed to /hmpc/humanoid/cost_weights on domain 106"),
            std::string::npos)
      << output;
  EXPECT_TRUE(std::filesystem::exists(dir + "/learned.weights")) << "the learned weights are kept";
}

}  // namespace
