// Each protocol's DBC (common/protocol/hmpc_forearm.dbc, hmpc_joint.dbc) against its header's
// tables: every message and signal, with id, length, sender, cycle time, bit layout, scaling,
// range, unit, receivers and value descriptions, and nothing in one that is not in the other.
// The DBC is read by a small parser here, so the check needs no external tool.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "hmpc/protocol/forearm_protocol.hpp"
#include "hmpc/protocol/joint_protocol.hpp"

#if !defined(HMPC_FOREARM_DBC) || !defined(HMPC_JOINT_DBC)
#error "HMPC_FOREARM_DBC and HMPC_JOINT_DBC must name the DBC files (set in tests/CMakeLists.txt)"
#endif

namespace {

using hmpc::protocol::ByteOrder;
using hmpc::protocol::frame_id;
using hmpc::protocol::frame_spec;
using hmpc::protocol::signal_spec;
using hmpc::protocol::to_string;

struct DbcSignal {
  std::string name;
  int start_bit = 0;
  int length = 0;
  char byte_order = '?';  // '1' little-endian (Intel), '0' big-endian (Motorola)
  char sign = '?';        // '+' unsigned, '-' signed
  double factor = 0;
  double offset = 0;
  double min = 0;
  double max = 0;
  std::string unit;
  std::set<std::string> receivers;
};

struct DbcMessage {
  std::string name;
  int dlc = 0;
  std::string sender;
  std::map<std::string, DbcSignal> signals;
  bool has_cycle_time = false;
  int cycle_time_ms = 0;
};

struct Dbc {
  bool has_version = false;
  std::set<std::string> nodes;
  std::map<std::uint32_t, DbcMessage> messages;
  int default_cycle_time_ms = 0;
  // (message id, signal name) -> raw value -> description
  std::map<std::pair<std::uint32_t, std::string>, std::map<std::uint32_t, std::string>> values;
  std::vector<std::string> errors;
};

std::set<std::string> words(const std::string& text, char separator) {
  std::set<std::string> out;
  std::istringstream in(text);
  std::string word;
  while (std::getline(in, word, separator)) {
    const auto first = word.find_first_not_of(" \t;");
    const auto last = word.find_last_not_of(" \t;");
    if (first != std::string::npos) out.insert(word.substr(first, last - first + 1));
  }
  return out;
}

// "BO_ 256 ModeCommand: 8 HOST"
bool parse_message(const std::string& line, std::uint32_t& id, DbcMessage& m) {
  std::istringstream in(line);
  std::string keyword;
  std::string name;
  if (!(in >> keyword >> id >> name) || keyword != "BO_") return false;
  if (name.back() == ':') {
    name.pop_back();
  } else {
    std::string colon;
    if (!(in >> colon) || colon != ":") return false;
  }
  m.name = name;
  return static_cast<bool>(in >> m.dlc >> m.sender);
}

// " SG_ theta : 16|16@1- (0.0001,0) [-3.1416|3.1416] "rad" BOARD"
bool parse_signal(const std::string& line, DbcSignal& s) {
  std::istringstream in(line);
  std::string keyword;
  std::string colon;
  std::string layout;
  std::string scaling;
  std::string range;
  if (!(in >> keyword >> s.name >> colon >> layout >> scaling >> range >> std::quoted(s.unit))) {
    return false;
  }
  if (keyword != "SG_" || colon != ":") return false;
  char extra = 0;
  if (std::sscanf(layout.c_str(), "%d|%d@%c%c%c", &s.start_bit, &s.length, &s.byte_order, &s.sign,
                  &extra) != 4 ||
      std::sscanf(scaling.c_str(), "(%lf,%lf)%c", &s.factor, &s.offset, &extra) != 2 ||
      std::sscanf(range.c_str(), "[%lf|%lf]%c", &s.min, &s.max, &extra) != 2) {
    return false;
  }
  std::string receivers;
  std::getline(in, receivers);
  s.receivers = words(receivers, ',');
  return !s.receivers.empty();
}

Dbc parse_dbc(std::istream& in) {
  Dbc dbc;
  DbcMessage* current = nullptr;
  std::string line;
  int number = 0;
  auto error = [&](const std::string& what) {
    dbc.errors.push_back("line " + std::to_string(number) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto text_start = line.find_first_not_of(" \t");
    const std::string text = text_start == std::string::npos ? "" : line.substr(text_start);
    std::istringstream tokens(text);
    std::string keyword;
    tokens >> keyword;
    // Indented lines are a message's signals or the keyword list of NS_.
    if (text_start != 0 && keyword != "SG_") continue;
    if (keyword == "VERSION") {
      dbc.has_version = true;
    } else if (keyword == "BU_:" || keyword == "BU_") {
      dbc.nodes = words(text.substr(text.find(':') + 1), ' ');
    } else if (keyword == "BO_") {
      std::uint32_t id = 0;
      DbcMessage m;
      if (!parse_message(text, id, m)) {
        error("BO_ not understood: " + line);
        continue;
      }
      current = &dbc.messages[id];
      current->name = m.name;
      current->dlc = m.dlc;
      current->sender = m.sender;
      continue;
    } else if (keyword == "SG_") {
      DbcSignal s;
      if (current == nullptr || !parse_signal(text, s)) {
        error("SG_ not understood or outside a BO_: " + line);
      } else if (!current->signals.emplace(s.name, s).second) {
        error("signal " + s.name + " twice");
      }
      continue;
    } else if (keyword == "BA_DEF_DEF_") {
      std::string attribute;
      if (tokens >> std::quoted(attribute) && attribute == "GenMsgCycleTime") {
        tokens >> dbc.default_cycle_time_ms;
      }
    } else if (keyword == "BA_") {
      std::string attribute;
      std::string object;
      std::uint32_t id = 0;
      int value = 0;
      if (!(tokens >> std::quoted(attribute) >> object >> id >> value)) {
        error("BA_ not understood: " + line);
      } else if (attribute == "GenMsgCycleTime" && object == "BO_") {
        dbc.messages[id].has_cycle_time = true;
        dbc.messages[id].cycle_time_ms = value;
      }
    } else if (keyword == "VAL_") {
      std::uint32_t id = 0;
      std::string name;
      if (!(tokens >> id >> name)) {
        error("VAL_ not understood: " + line);
        continue;
      }
      auto& table = dbc.values[{id, name}];
      std::string value;
      std::string description;
      while (tokens >> value && value != ";") {
        if (!(tokens >> std::quoted(description))) {
          error("VAL_ pair not understood: " + line);
          break;
        }
        table[static_cast<std::uint32_t>(std::stoul(value))] = description;
      }
    }
    current = nullptr;  // a message's SG_ lines follow it directly
  }
  return dbc;
}

struct Forearm {
  using Description = hmpc::forearm_protocol::Description;
  static constexpr const char* kPath = HMPC_FOREARM_DBC;
  static std::set<std::string> nodes() { return {"HOST", "BOARD", "PLANT"}; }
};
struct Joint {
  using Description = hmpc::joint_protocol::Description;
  static constexpr const char* kPath = HMPC_JOINT_DBC;
  static std::set<std::string> nodes() { return {"HOST", "BOARD", "PLANT", "IMU"}; }
};

template <class Protocol>
Dbc load() {
  std::ifstream file(Protocol::kPath);
  EXPECT_TRUE(file.good()) << "cannot open " << Protocol::kPath;
  return parse_dbc(file);
}

template <class Protocol>
class DbcFile : public ::testing::Test {};
using Protocols = ::testing::Types<Forearm, Joint>;
TYPED_TEST_SUITE(DbcFile, Protocols);

TYPED_TEST(DbcFile, ParsesWithHeaderNodesAndNoUnknownLines) {
  const Dbc dbc = load<TypeParam>();
  EXPECT_TRUE(dbc.has_version);
  EXPECT_EQ(dbc.nodes, TypeParam::nodes());
  for (const std::string& error : dbc.errors) ADD_FAILURE() << error;
}

// The DBC shows node 0's identifiers.
TYPED_TEST(DbcFile, MessagesMatchTheFrameTable) {
  using P = typename TypeParam::Description;
  const Dbc dbc = load<TypeParam>();
  EXPECT_EQ(dbc.messages.size(), std::size(P::kFrames));
  for (const auto& frame : P::kFrames) {
    const auto it = dbc.messages.find(frame_id(frame.type, 0));
    ASSERT_NE(it, dbc.messages.end()) << frame.name << " missing";
    const DbcMessage& m = it->second;
    EXPECT_EQ(m.name, frame.name);
    EXPECT_EQ(m.dlc, frame.dlc) << frame.name;
    EXPECT_EQ(m.sender, to_string(frame.sender)) << frame.name;
    EXPECT_EQ(m.has_cycle_time ? m.cycle_time_ms : dbc.default_cycle_time_ms, frame.cycle_time_ms)
        << frame.name;
  }
}

TYPED_TEST(DbcFile, SignalsMatchTheSignalTable) {
  using P = typename TypeParam::Description;
  const Dbc dbc = load<TypeParam>();
  for (const auto& frame : P::kFrames) {
    const auto it = dbc.messages.find(frame_id(frame.type, 0));
    ASSERT_NE(it, dbc.messages.end()) << frame.name;
    const DbcMessage& m = it->second;
    std::set<std::string> in_table;
    for (const auto& s : P::kSignals) {
      if (s.frame != frame.type) continue;
      in_table.insert(s.name);
      const auto found = m.signals.find(s.name);
      if (found == m.signals.end()) {
        ADD_FAILURE() << frame.name << "." << s.name << " is in the header but not in the DBC";
        continue;
      }
      const DbcSignal& d = found->second;
      SCOPED_TRACE(std::string(frame.name) + "." + s.name);
      EXPECT_EQ(d.start_bit, s.start_bit);
      EXPECT_EQ(d.length, s.length);
      EXPECT_EQ(d.byte_order, s.byte_order == ByteOrder::kLittleEndian ? '1' : '0');
      EXPECT_EQ(d.sign, s.is_signed ? '-' : '+');
      EXPECT_EQ(d.factor, s.factor);
      EXPECT_EQ(d.offset, s.offset);
      EXPECT_EQ(d.min, s.min);
      EXPECT_EQ(d.max, s.max);
      EXPECT_EQ(d.unit, s.unit);
      EXPECT_EQ(d.receivers, std::set<std::string>{to_string(frame.receiver)});
    }
    for (const auto& [name, unused] : m.signals) {
      EXPECT_TRUE(in_table.count(name))
          << frame.name << "." << name << " is in the DBC but not in the header";
    }
  }
}

TYPED_TEST(DbcFile, ValueTablesMatchTheEnumerations) {
  using P = typename TypeParam::Description;
  const Dbc dbc = load<TypeParam>();
  std::size_t enumerated = 0;
  for (const auto& s : P::kSignals) {
    const auto it = dbc.values.find({frame_id(s.frame, 0), s.name});
    if (s.values.count == 0) {
      EXPECT_EQ(it, dbc.values.end()) << s.name << " has a VAL_ table but is no enumeration";
      continue;
    }
    ++enumerated;
    ASSERT_NE(it, dbc.values.end())
        << frame_spec(s.frame).name << "." << s.name << " has no VAL_ table";
    std::map<std::uint32_t, std::string> expected;
    for (std::uint8_t i = 0; i < s.values.count; ++i) {
      expected[s.values.values[i].value] = s.values.values[i].name;
    }
    EXPECT_EQ(it->second, expected) << frame_spec(s.frame).name << "." << s.name;
  }
  EXPECT_EQ(dbc.values.size(), enumerated);
}

// The parser itself: a signal with the wrong layout must be found.
TEST(DbcParser, SeesADifference) {
  std::istringstream text(
      "VERSION \"\"\nBU_: HOST BOARD PLANT\nBO_ 257 Sensor: 8 PLANT\n"
      " SG_ theta : 16|16@1+ (0.0001,0) [-3.1416|3.1416] \"rad\" BOARD\n"
      "VAL_ 257 theta 1 \"one\" 0 \"zero\" ;\n");
  const Dbc dbc = parse_dbc(text);
  ASSERT_TRUE(dbc.errors.empty());
  const DbcSignal& theta = dbc.messages.at(257).signals.at("theta");
  EXPECT_EQ(theta.sign, '+');
  EXPECT_NE(theta.sign,
            signal_spec(hmpc::forearm_protocol::Signal::kSensorTheta).is_signed ? '-' : '+');
  EXPECT_EQ(theta.factor, 0.0001);
  EXPECT_EQ(dbc.values.at({257, "theta"}).at(1), "one");
}

}  // namespace
