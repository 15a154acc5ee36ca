#include "hmpc/humanoid/motion.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <vector>

namespace hmpc::humanoid {
namespace {

constexpr const char* kVersionLine = "hmpc-humanoid-motion 1";

struct KeySpec {
  const char* name;
  int size;               // numbers in the value
  bool optional = false;  // may be left out
};

// The keys of each section, with the number of values each takes (motion.hpp).
const std::map<std::string, std::vector<KeySpec>>& section_keys() {
  static const std::map<std::string, std::vector<KeySpec>> keys{
      {"motion", {{"duration", 1}, {"chair", 3}, {"gait", 3}, {"model_substep", 1, true}}},
      {"weights",
       {{"w_HAA", 1},
        {"w_HFE", 1},
        {"w_KFE", 1},
        {"w_AFE", 1},
        {"w_q1", 1},
        {"w_q2", 1},
        {"w_q3", 1},
        {"w_q4", 1},
        {"w_height", 1},
        {"w_vx", 1},
        {"w_vy", 1},
        {"w_vz", 1},
        {"w_alpha", 1},
        {"w_beta", 1},
        {"w_omega_x", 1},
        {"w_omega_y", 1},
        {"w_omega_z", 1},
        {"w_fast", 1},
        {"w_fast_control", 1},
        {"w_foot", 1},
        {"w_position", 1, true},
        {"w_joint_velocity", 1, true},
        {"w_torque_change", 1, true}}},
      {"phase",
       {{"start", 1}, {"attitude", 3}, {"height", 1}, {"velocity", 3}, {"squat", 2, true}}},
      {"reach", {{"target", 3}, {"start", 1}, {"w_reach", 1}, {"w_SFE", 1}}},
  };
  return keys;
}

struct Entry {
  int line = 0;
  std::string text;
};

struct Section {
  std::string name;
  int line = 0;
  std::map<std::string, Entry> entries;
};

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(int line, const std::string& key, const std::string& what) const {
    std::ostringstream message;
    message << source_ << ":" << line << ": ";
    if (!key.empty()) message << key << ": ";
    message << what;
    throw MotionFileError(message.str());
  }

  [[noreturn]] void fail_file(const std::string& what) const {
    throw MotionFileError(source_ + ": " + what);
  }

  // One number: a decimal, optionally followed by `pi` (a bare `pi` or `-pi` is +-1 pi).
  double number(const Entry& entry, const std::string& key, const std::string& token) const {
    std::string digits = token;
    double factor = 1.0;
    if (digits.size() >= 2 && digits.compare(digits.size() - 2, 2, "pi") == 0) {
      digits.resize(digits.size() - 2);
      factor = M_PI;
      if (digits.empty() || digits == "+") digits = "1";
      if (digits == "-") digits = "-1";
    }
    char* end = nullptr;
    const double value = std::strtod(digits.c_str(), &end);
    if (digits.empty() || end != digits.c_str() + digits.size())
      fail(entry.line, key, "not a number: '" + token + "'");
    if (!std::isfinite(value)) fail(entry.line, key, "not finite: '" + token + "'");
    return value * factor;
  }

  std::vector<double> numbers(const Section& section, const std::string& key) const {
    const Entry& entry = section.entries.at(key);
    std::istringstream in(entry.text);
    std::vector<double> values;
    for (std::string token; in >> token;) values.push_back(number(entry, key, token));
    int size = 0;
    for (const KeySpec& spec : section_keys().at(section.name))
      if (key == spec.name) size = spec.size;
    if (static_cast<int>(values.size()) != size) {
      fail(entry.line, key,
           "expected " + std::to_string(size) + (size == 1 ? " number" : " numbers") + ", got '" +
               entry.text + "'");
    }
    return values;
  }

  double scalar(const Section& section, const std::string& key) const {
    return numbers(section, key)[0];
  }
  Eigen::Vector3d vector3(const Section& section, const std::string& key) const {
    const std::vector<double> v = numbers(section, key);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  }
  double weight(const Section& section, const std::string& key) const {
    const double w = scalar(section, key);
    if (w < 0.0) fail(section.entries.at(key).line, key, "a weight must be >= 0");
    return w;
  }
  int line_of(const Section& section, const std::string& key) const {
    return section.entries.at(key).line;
  }

  std::vector<Section> sections(std::istream& in) const {
    std::vector<Section> sections;
    bool version_seen = false;
    int line_number = 0;
    for (std::string line; std::getline(in, line);) {
      ++line_number;
      const std::string text = trim(line.substr(0, line.find('#')));
      if (text.empty()) continue;
      if (!version_seen) {
        if (text != kVersionLine)
          fail(line_number, "",
               "expected the version line '" + std::string(kVersionLine) + "', got '" + text + "'");
        version_seen = true;
        continue;
      }
      if (text.front() == '[') {
        if (text.back() != ']') fail(line_number, "", "malformed section header '" + text + "'");
        Section section;
        section.name = trim(text.substr(1, text.size() - 2));
        section.line = line_number;
        if (section_keys().count(section.name) == 0)
          fail(line_number, "", "unknown section [" + section.name + "]");
        sections.push_back(section);
        continue;
      }
      const auto equals = text.find('=');
      if (equals == std::string::npos)
        fail(line_number, "", "expected 'key = value', got '" + text + "'");
      const std::string key = trim(text.substr(0, equals));
      const std::string value = trim(text.substr(equals + 1));
      if (key.empty()) fail(line_number, "", "missing key before '='");
      if (sections.empty()) fail(line_number, key, "setting outside a section");
      Section& section = sections.back();
      bool known = false;
      for (const KeySpec& spec : section_keys().at(section.name)) known = known || key == spec.name;
      if (!known) fail(line_number, key, "unknown key in [" + section.name + "]");
      if (value.empty()) fail(line_number, key, "missing value");
      if (!section.entries.emplace(key, Entry{line_number, value}).second) {
        fail(line_number, key,
             "duplicate key (first set on line " + std::to_string(section.entries.at(key).line) +
                 ")");
      }
    }
    if (!version_seen)
      fail(line_number, "",
           "empty file: expected the version line '" + std::string(kVersionLine) + "'");
    for (const Section& section : sections) {
      for (const KeySpec& spec : section_keys().at(section.name)) {
        if (!spec.optional && section.entries.count(spec.name) == 0)
          fail(section.line, spec.name, "missing key in [" + section.name + "]");
      }
    }
    return sections;
  }

 private:
  static std::string trim(const std::string& s) {
    const auto first = s.find_first_not_of(" \t\r");
    if (first == std::string::npos) return "";
    return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
  }

  std::string source_;
};

}  // namespace

const Phase& Motion::phase_at(double t) const {
  // The first phase after t, by bisection: a demonstration's motion has one phase per step.
  const auto later =
      std::upper_bound(phases.begin() + 1, phases.begin() + std::max(1, phase_count), t,
                       [](double time, const Phase& phase) { return time < phase.start; });
  return *(later - 1);
}

double Phase::height_at(double t) const {
  if (squat_period <= 0.0) return height;
  return height - 0.5 * squat_depth * (1.0 - std::cos(2 * M_PI * (t - start) / squat_period));
}

Eigen::Vector3d Phase::velocity_at(double t) const {
  Eigen::Vector3d v = velocity;
  if (squat_period > 0.0) {
    const double omega = 2 * M_PI / squat_period;
    v.z() -= 0.5 * squat_depth * omega * std::sin(omega * (t - start));
  }
  return v;
}

double Gait::foot_height(double t, int foot) const {
  if (period <= 0.0) return 0.0;
  const double cycle = t / period - std::floor(t / period);
  double progress = cycle - 0.5 * foot;
  if (progress < 0.0) progress += 1.0;
  progress /= swing_fraction;
  return progress < 1.0 ? swing_height * std::sin(M_PI * progress) : 0.0;
}

Motion parse_motion(std::istream& in, const std::string& source) {
  const Reader reader(source);
  const std::vector<Section> sections = reader.sections(in);
  Motion motion;
  const Section* motion_section = nullptr;
  const Section* weights_section = nullptr;
  const Section* reach_section = nullptr;
  for (const Section& section : sections) {
    if (section.name == "phase") {
      if (motion.phase_count == kMaxPhases)
        reader.fail(section.line, "", "more than " + std::to_string(kMaxPhases) + " phases");
      Phase& phase = motion.phases[motion.phase_count];
      phase.start = reader.scalar(section, "start");
      const int start_line = reader.line_of(section, "start");
      if (motion.phase_count == 0 && phase.start != 0.0)
        reader.fail(start_line, "start", "the first phase must start at 0");
      if (motion.phase_count > 0 && phase.start <= motion.phases[motion.phase_count - 1].start)
        reader.fail(start_line, "start",
                    "phases out of order: must start after the previous phase");
      phase.attitude = reader.vector3(section, "attitude");
      phase.height = reader.scalar(section, "height");
      phase.velocity = reader.vector3(section, "velocity");
      if (section.entries.count("squat") != 0) {
        const std::vector<double> squat = reader.numbers(section, "squat");
        if (squat[1] <= 0.0) {
          reader.fail(reader.line_of(section, "squat"), "squat", "the period must be > 0");
        }
        phase.squat_depth = squat[0];
        phase.squat_period = squat[1];
      }
      ++motion.phase_count;
      continue;
    }
    const Section*& slot = section.name == "motion"    ? motion_section
                           : section.name == "weights" ? weights_section
                                                       : reach_section;
    if (slot != nullptr) {
      reader.fail(section.line, "",
                  "section [" + section.name + "] repeated (first on line " +
                      std::to_string(slot->line) + ")");
    }
    slot = &section;
  }
  if (motion_section == nullptr) reader.fail_file("missing section [motion]");
  if (weights_section == nullptr) reader.fail_file("missing section [weights]");
  if (motion.phase_count == 0) reader.fail_file("missing section [phase]");

  const Section& m = *motion_section;
  motion.duration = reader.scalar(m, "duration");
  if (motion.duration <= 0.0) reader.fail(reader.line_of(m, "duration"), "duration", "must be > 0");
  if (m.entries.at("chair").text != "none") {
    const std::vector<double> seat = reader.numbers(m, "chair");
    motion.chair = true;
    motion.seat_height = seat[0];
    motion.seat_x_min = seat[1];
    motion.seat_x_max = seat[2];
    if (motion.seat_height <= 0.0 || motion.seat_x_min >= motion.seat_x_max) {
      reader.fail(reader.line_of(m, "chair"), "chair",
                  "expected 'none' or 'height x_min x_max' with height > 0 and x_min < x_max");
    }
  }

  if (m.entries.at("gait").text != "none") {
    const std::vector<double> gait = reader.numbers(m, "gait");
    motion.gait = Gait{gait[0], gait[1], gait[2]};
    if (gait[0] <= 0.0 || gait[1] <= 0.0 || gait[2] <= 0.0 || gait[2] > 1.0) {
      reader.fail(reader.line_of(m, "gait"), "gait",
                  "expected 'none' or 'period swing_height swing_fraction' with period > 0, "
                  "swing_height > 0 and 0 < swing_fraction <= 1");
    }
  }

  if (m.entries.count("model_substep") != 0) {
    motion.model_substep = reader.scalar(m, "model_substep");
    if (motion.model_substep <= 0.0 || motion.model_substep > kMaxModelSubstep) {
      char bound[64];
      std::snprintf(bound, sizeof bound, "must be > 0 s and at most %g s", kMaxModelSubstep);
      reader.fail(reader.line_of(m, "model_substep"), "model_substep", bound);
    }
  }

  const Section& w = *weights_section;
  CostWeights& weights = motion.weights;
  weights.control = {reader.weight(w, "w_HAA"), reader.weight(w, "w_HFE"),
                     reader.weight(w, "w_KFE"), reader.weight(w, "w_AFE")};
  // Element by element: a missing key throws, which must not leave an Eigen comma
  // initializer half done, and keys are reported in file order.
  for (int i = 0; i < 4; ++i) weights.attitude(i) = reader.weight(w, "w_q" + std::to_string(i + 1));
  weights.height = reader.weight(w, "w_height");
  const char* const axes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) weights.velocity(i) = reader.weight(w, std::string("w_v") + axes[i]);
  weights.alpha = reader.weight(w, "w_alpha");
  weights.beta = reader.weight(w, "w_beta");
  for (int i = 0; i < 3; ++i) {
    weights.angular_velocity(i) = reader.weight(w, std::string("w_omega_") + axes[i]);
  }
  weights.fast = reader.weight(w, "w_fast");
  weights.fast_control = reader.weight(w, "w_fast_control");
  weights.foot = reader.weight(w, "w_foot");
  if (w.entries.count("w_position") != 0) weights.position = reader.weight(w, "w_position");
  if (w.entries.count("w_joint_velocity") != 0) {
    weights.joint_velocity = reader.weight(w, "w_joint_velocity");
  }
  if (w.entries.count("w_torque_change") != 0) {
    weights.torque_change = reader.weight(w, "w_torque_change");
  }

  if (reach_section != nullptr) {
    const Section& r = *reach_section;
    Reach& reach = motion.reach;
    reach.active = true;
    reach.target = reader.vector3(r, "target");
    reach.start = reader.scalar(r, "start");
    if (reach.start < 0.0) reader.fail(reader.line_of(r, "start"), "start", "must be >= 0");
    reach.weight = reader.weight(r, "w_reach");
    reach.control = reader.weight(r, "w_SFE");
  }
  return motion;
}

std::string motion_path(const std::string& name_or_path, const std::string& shipped_dir) {
  if (name_or_path.find('/') != std::string::npos ||
      name_or_path.find(".motion") != std::string::npos) {
    return name_or_path;
  }
  return shipped_dir + "/" + name_or_path + ".motion";
}

void write_motion(std::ostream& out, const Motion& motion, const std::string& comment) {
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out << "# " << line << '\n';
  char buffer[96];
  const auto number = [&buffer](double v) {
    std::snprintf(buffer, sizeof buffer, "%.17g", v);
    return std::string(buffer);
  };
  const auto vector3 = [&number](const Eigen::Vector3d& v) {
    return number(v.x()) + " " + number(v.y()) + " " + number(v.z());
  };
  const CostWeights& w = motion.weights;
  out << kVersionLine << "\n\n[motion]\nduration = " << number(motion.duration) << '\n';
  out << "chair = "
      << (motion.chair ? number(motion.seat_height) + " " + number(motion.seat_x_min) + " " +
                             number(motion.seat_x_max)
                       : std::string("none"))
      << '\n';
  out << "gait = "
      << (motion.gait.period > 0.0
              ? number(motion.gait.period) + " " + number(motion.gait.swing_height) + " " +
                    number(motion.gait.swing_fraction)
              : std::string("none"))
      << '\n';
  if (motion.model_substep > 0.0) out << "model_substep = " << number(motion.model_substep) << '\n';
  out << "\n[weights]\n";
  const char* const joints[] = {"HAA", "HFE", "KFE", "AFE"};
  for (int j = 0; j < 4; ++j) out << "w_" << joints[j] << " = " << number(w.control[j]) << '\n';
  for (int i = 0; i < 4; ++i) out << "w_q" << i + 1 << " = " << number(w.attitude[i]) << '\n';
  out << "w_height = " << number(w.height) << '\n';
  const char* const axes[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) out << "w_v" << axes[i] << " = " << number(w.velocity[i]) << '\n';
  out << "w_alpha = " << number(w.alpha) << "\nw_beta = " << number(w.beta) << '\n';
  for (int i = 0; i < 3; ++i)
    out << "w_omega_" << axes[i] << " = " << number(w.angular_velocity[i]) << '\n';
  out << "w_fast = " << number(w.fast) << "\nw_fast_control = " << number(w.fast_control)
      << "\nw_foot = " << number(w.foot) << '\n';
  if (w.position > 0.0) out << "w_position = " << number(w.position) << '\n';
  if (w.joint_velocity > 0.0) out << "w_joint_velocity = " << number(w.joint_velocity) << '\n';
  if (w.torque_change > 0.0) out << "w_torque_change = " << number(w.torque_change) << '\n';
  for (int k = 0; k < motion.phase_count; ++k) {
    const Phase& p = motion.phases[k];
    out << "\n[phase]\nstart = " << number(p.start) << "\nattitude = " << vector3(p.attitude)
        << "\nheight = " << number(p.height) << "\nvelocity = " << vector3(p.velocity) << '\n';
    if (p.squat_period > 0.0) {
      out << "squat = " << number(p.squat_depth) << ' ' << number(p.squat_period) << '\n';
    }
  }
  if (motion.reach.active) {
    out << "\n[reach]\ntarget = " << vector3(motion.reach.target)
        << "\nstart = " << number(motion.reach.start)
        << "\nw_reach = " << number(motion.reach.weight)
        << "\nw_SFE = " << number(motion.reach.control) << '\n';
  }
}

Motion load_motion(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw MotionFileError(path + ": cannot open the motion file");
  return parse_motion(in, path);
}

Eigen::Vector4d attitude_quaternion(const Eigen::Vector3d& a) {
  // q = q_z(xi) q_y(theta) q_x(phi), each (cos(angle/2), sin(angle/2) axis).
  const double cr = std::cos(0.5 * a.x()), sr = std::sin(0.5 * a.x());
  const double cp = std::cos(0.5 * a.y()), sp = std::sin(0.5 * a.y());
  const double cy = std::cos(0.5 * a.z()), sy = std::sin(0.5 * a.z());
  return Eigen::Vector4d(cy * cp * cr + sy * sp * sr, cy * cp * sr - sy * sp * cr,
                         cy * sp * cr + sy * cp * sr, sy * cp * cr - cy * sp * sr);
}

}  // namespace hmpc::humanoid
