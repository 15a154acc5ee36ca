#include "hmpc/host/humanoid_replay.hpp"

#include <cmath>
#include <vector>

#include "hmpc/platform/linux/candump_log.hpp"
#include "hmpc/platform/linux/protocol_frames.hpp"

namespace hmpc::host {

namespace {

namespace jp = hmpc::joint_protocol;

struct Logged {
  std::uint32_t tick = 0;
  jp::Frame frame;
  bool sent = false;  // by the host
};

bool sent_by_host(const jp::Frame& f) {
  jp::FrameType type{};
  jp::NodeId node = 0;
  return jp::identify(f.id, type, node) && jp::frame_spec(type).sender == protocol::Endpoint::kHost;
}

std::string describe(const jp::Frame& f) {
  char text[32];
  platform::format_candump_frame(platform::to_can_frame(f), text);
  return text;
}

bool same(const jp::Frame& a, const jp::Frame& b) {
  if (a.id != b.id || a.dlc != b.dlc) return false;
  for (int i = 0; i < a.dlc; ++i) {
    if (a.data[std::size_t(i)] != b.data[std::size_t(i)]) return false;
  }
  return true;
}

}  // namespace

bool replay_lockstep_log(std::istream& log, HumanoidHost& host, ReplayReport& report,
                         std::string& error,
                         const std::function<void(std::uint32_t)>& before_tick) {
  report = {};
  std::vector<Logged> lines;
  std::string line, interface;
  while (std::getline(log, line)) {
    double t = 0;
    platform::CanFrame raw{};
    Logged l;
    if (!platform::read_candump_line(line, t, interface, raw) || !(t >= 0) || t > 4e6 ||
        !platform::to_protocol_frame(raw, l.frame)) {
      ++report.skipped_lines;
      continue;
    }
    l.tick = std::uint32_t(std::lround(t * 1e3));
    if (!lines.empty() && l.tick < lines.back().tick) {
      error = "the log's stamps go backwards at line " + std::to_string(lines.size() + 1);
      return false;
    }
    l.sent = sent_by_host(l.frame);
    report.logged_sent += l.sent ? 1 : 0;
    lines.push_back(l);
  }
  if (lines.empty()) {
    error = "the log holds no frame";
    return false;
  }
  std::size_t next = 0;
  std::vector<const jp::Frame*> expected;  // the run's frames of one tick
  for (std::uint32_t tick = 0; tick <= lines.back().tick; ++tick) {
    // What the host heard before this tick, then the tick; the run's frames of this tick.
    expected.clear();
    for (; next < lines.size() && lines[next].tick == tick; ++next) {
      if (lines[next].sent) {
        expected.push_back(&lines[next].frame);
      } else {
        host.on_frame(lines[next].frame, tick == 0 ? 0 : tick - 1);
        ++report.heard;
      }
    }
    std::size_t matched = 0;
    if (before_tick) before_tick(tick);
    host.tick(tick, true, [&](const jp::Frame& f) {
      ++report.sent;
      const bool ok = matched < expected.size() && same(f, *expected[matched]);
      if (!ok && report.mismatches++ == 0) {
        report.first_mismatch_tick = tick;
        report.first_mismatch =
            "sent " + describe(f) + ", the run " +
            (matched < expected.size() ? describe(*expected[matched]) : std::string("nothing"));
      }
      ++matched;
    });
    if (matched < expected.size()) {
      if (report.mismatches == 0) {
        report.first_mismatch_tick = tick;
        report.first_mismatch = "sent nothing, the run " + describe(*expected[matched]);
      }
      report.mismatches += expected.size() - matched;
    }
    ++report.ticks;
  }
  return true;
}

}  // namespace hmpc::host
