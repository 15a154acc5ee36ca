#include "hmpc/ioc/files.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace hmpc::ioc {

namespace {

constexpr const char* kWeightsVersion = "hmpc-ioc-weights 1";
constexpr const char* kDemonstrationsVersion = "hmpc-ioc-demonstrations 1";
constexpr int kStateColumns = humanoid::kStateSize, kInputColumns = humanoid::kJoints;
constexpr int kColumns = 2 + kStateColumns + kInputColumns;
constexpr double kTimeTolerance = 1e-6;  // [s], of rows 30 ms apart (written with 17 digits)
constexpr double kQuaternionTolerance = 1e-6;

[[noreturn]] void fail(const std::string& source, int line, const std::string& what) {
  throw IocFileError(source + ":" + std::to_string(line) + ": " + what);
}

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t\r");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t\r") - begin + 1);
}

// A whole field as a finite number, or false.
bool to_number(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return *end == '\0' && std::isfinite(value);
}

std::string header_line() {
  std::ostringstream header;
  header << "demo,time";
  for (int i = 0; i < kStateColumns; ++i) header << ",x" << i;
  for (int i = 0; i < kInputColumns; ++i) header << ",u" << i;
  return header.str();
}

std::ifstream open(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw IocFileError(path + ": cannot be opened");
  return in;
}

}  // namespace

void write_weights(std::ostream& out, const Weights& w, const std::string& comment) {
  out << kWeightsVersion << "\n";
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  out << std::setprecision(17);
  for (int k = 0; k < kWeightCount; ++k) out << kWeightNames[k] << " = " << w[k] << "\n";
}

Weights parse_weights(std::istream& in, const std::string& source) {
  Weights w;
  std::array<int, kWeightCount> seen{};  // line of each key, 0: not yet
  bool version = false;
  std::string raw;
  for (int line = 1; std::getline(in, raw); ++line) {
    const std::string text = trim(raw.substr(0, raw.find('#')));
    if (text.empty()) continue;
    if (!version) {
      if (text != kWeightsVersion)
        fail(source, line, "expected the version line '" + std::string(kWeightsVersion) + "'");
      version = true;
      continue;
    }
    const auto equals = text.find('=');
    if (equals == std::string::npos)
      fail(source, line, "expected 'key = value', got '" + text + "'");
    const std::string key = trim(text.substr(0, equals)), value = trim(text.substr(equals + 1));
    int k = 0;
    while (k < kWeightCount && key != kWeightNames[k]) ++k;
    if (k == kWeightCount) fail(source, line, "unknown weight '" + key + "'");
    if (seen[k] != 0) {
      std::string message = key;
      message += " given twice (first on line " + std::to_string(seen[k]);
      message += ')';
      fail(source, line, message);
    }
    if (!to_number(value, w[k])) {
      std::string message = key;
      message += ": not a finite number: '" + value + "'";
      fail(source, line, message);
    }
    if (!(w[k] > 0.0)) fail(source, line, key + ": a weight must be > 0");
    seen[k] = line;
  }
  if (!version) throw IocFileError(source + ": empty (no version line)");
  for (int k = 0; k < kWeightCount; ++k) {
    if (seen[k] == 0) throw IocFileError(source + ": missing " + kWeightNames[k]);
  }
  return w;
}

Weights load_weights(const std::string& path) {
  std::ifstream in = open(path);
  return parse_weights(in, path);
}

void write_demonstrations(std::ostream& out, const std::vector<Demonstration>& demonstrations) {
  out << kDemonstrationsVersion << "\n" << header_line() << "\n" << std::setprecision(17);
  for (std::size_t d = 0; d < demonstrations.size(); ++d) {
    const Demonstration& demo = demonstrations[d];
    for (std::size_t k = 0; k < demo.states.size(); ++k) {
      out << d << "," << demo.start_time + static_cast<double>(k) * humanoid::kCoarseStep;
      for (int i = 0; i < kStateColumns; ++i) out << "," << demo.states[k][i];
      for (int i = 0; i < kInputColumns; ++i) {
        out << ",";
        if (k < demo.inputs.size()) out << demo.inputs[k][i];
      }
      out << "\n";
    }
  }
}

std::vector<Demonstration> parse_demonstrations(std::istream& in, const std::string& source) {
  std::vector<Demonstration> demos;
  std::string raw;
  int line = 1;
  if (!std::getline(in, raw) || trim(raw) != kDemonstrationsVersion) {
    fail(source, line, "expected the version line '" + std::string(kDemonstrationsVersion) + "'");
  }
  ++line;
  if (!std::getline(in, raw) || trim(raw) != header_line()) {
    fail(source, line, "expected the header 'demo,time,x0,...,x28,u0,...,u7'");
  }
  bool open_inputs = false;  // the last row read had inputs: its demonstration needs another row
  double last_time = 0.0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string text = trim(raw);
    if (text.empty()) continue;
    std::vector<std::string> fields;
    std::istringstream row(text);
    for (std::string field; std::getline(row, field, ',');) fields.push_back(trim(field));
    if (!text.empty() && text.back() == ',') fields.emplace_back();
    if (static_cast<int>(fields.size()) != kColumns) {
      fail(
          source, line,
          "expected " + std::to_string(kColumns) + " fields, got " + std::to_string(fields.size()));
    }
    double id = 0.0, time = 0.0;
    if (!to_number(fields[0], id) || id != std::floor(id) || id < 0.0)
      fail(source, line, "demo: not a demonstration number");
    if (!to_number(fields[1], time)) fail(source, line, "time: not a finite number");
    // Numbered in order from 0: beyond the next number is out of order (and checked before the
    // number becomes an index, which a huge one could not).
    if (id > static_cast<double>(demos.size())) {
      char number[32];
      std::snprintf(number, sizeof number, "%g", id);
      fail(source, line,
           "demonstration " + std::string(number) + " out of order (expected at most " +
               std::to_string(demos.size()) + ")");
    }
    const bool new_demo = demos.empty() || static_cast<std::size_t>(id) != demos.size() - 1;
    if (new_demo) {
      if (static_cast<std::size_t>(id) != demos.size()) {
        fail(source, line,
             "demonstration " + std::to_string(static_cast<long>(id)) + " out of order (expected " +
                 std::to_string(demos.size()) + ")");
      }
      if (open_inputs)
        fail(source, line, "the previous demonstration's last row has inputs (it must have none)");
      demos.emplace_back();
      demos.back().start_time = time;
    } else {
      if (!open_inputs)
        fail(source, line, "a row after the demonstration's last row (the one without inputs)");
      if (std::abs(time - (last_time + humanoid::kCoarseStep)) > kTimeTolerance) {
        fail(source, line, "time: rows of a demonstration must be 0.03 s apart");
      }
    }
    Demonstration& demo = demos.back();
    humanoid::StateVector x;
    for (int i = 0; i < kStateColumns; ++i) {
      if (!to_number(fields[2 + i], x[i]))
        fail(source, line, "x" + std::to_string(i) + ": not a finite number");
    }
    if (std::abs(x.segment<4>(3).norm() - 1.0) > kQuaternionTolerance) {
      fail(source, line, "x3..x6: the quaternion is not of unit norm");
    }
    demo.states.push_back(x);
    const bool empty_inputs = fields[2 + kStateColumns].empty();
    if (empty_inputs) {
      for (int i = 0; i < kInputColumns; ++i) {
        if (!fields[2 + kStateColumns + i].empty()) fail(source, line, "inputs: all eight or none");
      }
      if (demo.inputs.empty()) fail(source, line, "a demonstration needs at least one input");
    } else {
      humanoid::JointVector u;
      for (int i = 0; i < kInputColumns; ++i) {
        if (!to_number(fields[2 + kStateColumns + i], u[i])) {
          fail(source, line, "u" + std::to_string(i) + ": not a finite number");
        }
      }
      demo.inputs.push_back(u);
    }
    open_inputs = !empty_inputs;
    last_time = time;
  }
  if (open_inputs)
    fail(source, line, "the file ends inside a demonstration (its last row must have no inputs)");
  if (demos.empty()) throw IocFileError(source + ": no demonstration");
  return demos;
}

std::vector<Demonstration> load_demonstrations(const std::string& path) {
  std::ifstream in = open(path);
  return parse_demonstrations(in, path);
}

}  // namespace hmpc::ioc
