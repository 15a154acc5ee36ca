// hmpc-forearm-hil: the forearm experiments of the thesis's Sec. 3.4 over CAN. For every
// strategy x target frequency x trial, runs board, host and Simbody plant in lock-step on vcan0
// (run it through hil/vcan/run-with-vcan.sh) and writes, to --out:
//   runs/<strategy>_<f>hz_<trial>/   each run's logs (plant.csv, host.csv) and program output
//   hil_runs.csv                     one row of figures per run
//   hil_summary.md                   mean and standard deviation over trials (Fig. 3.3 data)
//   hil_angle_<f>hz.png              joint angle vs target, Fine 4 ms, Coarse 20 ms, Two-stage
//                                    (Fig. 3.5)
//   hil_torques.png                  PAM and motor torque of the Two-stage runs (Fig. 3.9)
//   hil_cost.png, hil_error.png, hil_solve_time.png   bars per strategy and frequency
//                                    (Figs. 3.3b, 3.6, 3.3a)
//   hil_weight_sweep.png             with --weight-sweep: cost for w_v = 0.02, 0.002, 0.0002
//                                    at 1 Hz (Fig. 3.4)
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "hil_run.hpp"
#include "hmpc/cli/arguments.hpp"
#include "hmpc/models/forearm_target_range.hpp"
#include "hmpc/models/forearm_tracking_limit.hpp"

namespace {

namespace proto = hmpc::forearm_protocol;
using hmpc::hil::HilRunResult;
using hmpc::hil::HilRunSpec;

constexpr const char* kProgram = "hmpc-forearm-hil";
// The thesis's weights of Fig. 3.4.
constexpr double kSweepWeights[] = {0.02, 0.002, 0.0002};

struct Options {
  std::string out;
  std::vector<proto::Strategy> strategies{
      proto::Strategy::kFine4ms,    proto::Strategy::kFine8ms,  proto::Strategy::kCoarse20ms,
      proto::Strategy::kCoarse40ms, proto::Strategy::kTwoStage, proto::Strategy::kPamOnly};
  std::vector<double> frequencies{0.25, 0.5, 1.0};
  long trials = 5;
  double duration_s = 10;
  double noise = 1;
  hmpc::trajectory::TargetSpec target{};  // frequency_hz: each of `frequencies` in turn
  hmpc::hil::ForearmMismatch mismatch = hmpc::hil::kDemoMismatch;
  bool weight_sweep = false;
  // Each strategy as the thesis has it, offset-free (the board's --offset-free), or both.
  std::vector<bool> offset_free{false};
  // The Two-stage as the thesis has it, with the terminal rate term in both its stages (the
  // board's --terminal-rate), or both.
  std::vector<bool> terminal_rate{false};
  long jobs = 1;
};

void print_usage(std::FILE* out) {
  std::fprintf(
      out,
      "usage: hmpc-forearm-hil --out DIR [--strategies LIST] [--frequencies LIST] [--trials N]\n"
      "         [--duration S] [--noise SCALE] [--no-mismatch] [--mass-scale X]\n"
      "         [--friction-scale X] [--pam-time-scale X] [--weight-sweep] [--jobs N]\n"
      "         [--target SHAPE] [--amplitude-deg A] [--offset-deg D] [--chirp-to HZ]\n"
      "         [--step-at S] [--step-rate-deg-s R] [--target-file FILE] [--offset-free MODE]\n"
      "         [--terminal-rate MODE]\n"
      "Runs board, host and Simbody plant in lock-step over vcan0 for each strategy, target\n"
      "frequency (+-30 deg sinusoids by default) and trial (a different noise seed each), and\n"
      "writes CSV, a markdown table and PNG plots to DIR. Run it with vcan0 up, e.g. through\n"
      "hil/vcan/run-with-vcan.sh.\n"
      "  --strategies LIST   comma-separated: fine_4ms,fine_8ms,coarse_20ms,coarse_40ms,\n"
      "                      two_stage,pam_only (default: all)\n"
      "  --frequencies LIST  comma-separated Hz, each in (0, 2.5] (default 0.25,0.5,1); the\n"
      "                      sine's and the ramp's frequency, the chirp's start; none for a\n"
      "                      step or a file (their runs are listed at 0 Hz)\n"
      "  --trials N          1..20 (default 5)\n"
      "  --duration S        seconds of tracking per run, 1..60 (default 10)\n"
      "  --noise SCALE       sensor noise, times typical levels, 0..10 (default 1)\n"
      "  --no-mismatch       plant = controller's model (default: mass x1.05, friction x1.2,\n"
      "                      valve time constant x1.1)\n"
      "  --mass-scale X, --friction-scale X, --pam-time-scale X\n"
      "                      the plant's mismatch, each a factor in [0.5, 2] (after\n"
      "                      --no-mismatch: from 1)\n"
      "  --target SHAPE ...  the target of every run, as hmpc-forearm-host takes it (sine,\n"
      "                      step, ramp, chirp, file; see hmpc-forearm-host --help); checked\n"
      "                      against the joint's range and speed before any run\n"
      "  --weight-sweep      also run Two-stage, Coarse 20 ms and Fine 4 ms at 1 Hz for\n"
      "                      w_v = 0.02, 0.002, 0.0002 (Fig. 3.4)\n"
      "  --jobs N            runs at once, 1..4, each on its own board node id (default 1)\n"
      "  --offset-free MODE  off (the thesis's MPC, default), on (the boards' offset-free MPC:\n"
      "                      a disturbance observer, its estimate in the model), or both: each\n"
      "                      strategy twice, the offset-free rows named STRATEGY_offset_free\n"
      "  --terminal-rate MODE\n"
      "                      off (the thesis's Two-stage, default), on (its stages with the\n"
      "                      terminal rate term, the boards' --terminal-rate), or both: the\n"
      "                      Two-stage twice, the second named two_stage_terminal_rate; the\n"
      "                      other strategies run as the thesis has them in every mode\n");
}

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) out.push_back(item);
  return out;
}

std::string name(proto::Strategy s) {
  return proto::value_name(proto::kStrategyValues, std::uint32_t(s));
}

bool strategy_from_name(const std::string& text, proto::Strategy& out) {
  std::uint32_t value = 0;
  if (!proto::value_of(proto::kStrategyValues, text, value)) return false;
  out = proto::Strategy(value);
  return true;
}

hmpc::cli::ParseOutcome parse(int argc, char** argv, Options& o, std::string& error) {
  hmpc::cli::OptionParser p;
  bool frequencies_given = false;
  p.text("--out", [&](const std::string& v) -> std::string {
    if (v.empty()) return "--out needs a directory";
    o.out = v;
    return {};
  });
  p.text("--strategies", [&](const std::string& v) -> std::string {
    o.strategies.clear();
    for (const std::string& item : split(v)) {
      proto::Strategy s;
      if (!strategy_from_name(item, s)) return "--strategies: unknown strategy '" + item + "'";
      o.strategies.push_back(s);
    }
    return o.strategies.empty() ? "--strategies needs at least one strategy" : "";
  });
  p.text("--frequencies", [&](const std::string& v) -> std::string {
    frequencies_given = true;
    o.frequencies.clear();
    for (const std::string& item : split(v)) {
      double f = 0;
      if (!hmpc::cli::parse_number(item, 1e-3, 2.5, f))
        return hmpc::cli::bad_value("--frequencies", "a list of frequencies in (0, 2.5] Hz", v);
      o.frequencies.push_back(f);
    }
    return o.frequencies.empty() ? "--frequencies needs at least one frequency" : "";
  });
  p.integer("--trials", 1, 20, o.trials);
  p.number("--duration", 1, 60, "a number of seconds in [1, 60]", o.duration_s);
  p.number("--noise", 0, 10, "a scale in [0, 10]", o.noise);
  bool no_mismatch = false;
  p.flag("--no-mismatch", no_mismatch);
  double scales[3] = {NAN, NAN, NAN};
  p.number("--mass-scale", 0.5, 2, "a factor in [0.5, 2]", scales[0]);
  p.number("--friction-scale", 0.5, 2, "a factor in [0.5, 2]", scales[1]);
  p.number("--pam-time-scale", 0.5, 2, "a factor in [0.5, 2]", scales[2]);
  hmpc::trajectory::TargetSpec& target = o.target;
  p.text("--target", [&](const std::string& v) -> std::string {
    if (!hmpc::trajectory::shape_of(v, target.shape))
      return hmpc::cli::bad_value("--target", "one of sine step ramp chirp file", v);
    return {};
  });
  p.number("--amplitude-deg", -57, 57, "an amplitude in [-57, 57] deg", target.amplitude,
           M_PI / 180);
  p.number("--offset-deg", -57, 57, "an offset in [-57, 57] deg", target.offset, M_PI / 180);
  p.number("--chirp-to", 0, 5, "a frequency in [0, 5] Hz", target.chirp_end_hz);
  p.number("--step-at", 0, 60, "a time in [0, 60] s", target.step_at_s);
  target.step_rate = M_PI;  // hmpc-forearm-host's default
  p.number("--step-rate-deg-s", 1, 573, "a speed in [1, 573] deg/s", target.step_rate, M_PI / 180);
  p.text("--target-file", [&](const std::string& v) -> std::string {
    if (v.empty()) return "--target-file needs a file name";
    target.file = v;
    target.shape = hmpc::trajectory::TargetShape::kFile;
    return {};
  });
  p.flag("--weight-sweep", o.weight_sweep);
  const auto modes = [](const char* option, std::vector<bool>& out) {
    return [option, &out](const std::string& v) -> std::string {
      if (v == "off")
        out = {false};
      else if (v == "on")
        out = {true};
      else if (v == "both")
        out = {false, true};
      else
        return hmpc::cli::bad_value(option, "on, off or both", v);
      return {};
    };
  };
  p.text("--offset-free", modes("--offset-free", o.offset_free));
  p.text("--terminal-rate", modes("--terminal-rate", o.terminal_rate));
  p.integer("--jobs", 1, 4, o.jobs);
  const auto outcome = p.parse(argc, argv, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) return outcome;
  if (no_mismatch) o.mismatch = {1, 1, 1};
  if (!std::isnan(scales[0])) o.mismatch.mass_scale = scales[0];
  if (!std::isnan(scales[1])) o.mismatch.friction_scale = scales[1];
  if (!std::isnan(scales[2])) o.mismatch.pam_time_constant_scale = scales[2];
  if (o.out.empty()) {
    error = "--out is required";
    return hmpc::cli::ParseOutcome::kError;
  }
  const bool periodic = target.shape == hmpc::trajectory::TargetShape::kSine ||
                        target.shape == hmpc::trajectory::TargetShape::kRamp ||
                        target.shape == hmpc::trajectory::TargetShape::kChirp;
  if (!periodic) {
    if (frequencies_given) {
      error = std::string("--frequencies goes with sine, ramp and chirp targets, not ") +
              hmpc::trajectory::shape_name(target.shape);
      return hmpc::cli::ParseOutcome::kError;
    }
    o.frequencies = {0};
  }
  if (target.shape == hmpc::trajectory::TargetShape::kFile && target.file.empty()) {
    error = "--target file needs --target-file";
    return hmpc::cli::ParseOutcome::kError;
  }
  // Every run's target, checked before the first run starts.
  for (double f : o.frequencies) {
    hmpc::trajectory::TargetSpec t = target;
    t.frequency_hz = f;
    t.duration_s = o.duration_s;
    std::vector<hmpc::trajectory::TrajectoryPoint> points;
    std::string why;
    if (!hmpc::trajectory::make_points(t, hmpc::forearm::target_range(),
                                       hmpc::trajectory::kMaxPoints, points, why)) {
      error = "invalid target: " + why;
      return hmpc::cli::ParseOutcome::kError;
    }
  }
  return outcome;
}

// The runs' target and the plant's mismatch, as the summary states them.
std::string target_text(const hmpc::trajectory::TargetSpec& t) {
  using hmpc::trajectory::TargetShape;
  char text[256];
  const double deg = 180 / M_PI;
  switch (t.shape) {
    case TargetShape::kSine:
      std::snprintf(text, sizeof text, "+-%g deg sinusoids about %g deg", t.amplitude * deg,
                    t.offset * deg);
      break;
    case TargetShape::kStep:
      std::snprintf(text, sizeof text, "a step of %g deg from %g deg at %g s, at %g deg/s",
                    t.amplitude * deg, t.offset * deg, t.step_at_s, t.step_rate * deg);
      break;
    case TargetShape::kRamp:
      std::snprintf(text, sizeof text, "+-%g deg ramps (triangle waves) about %g deg",
                    t.amplitude * deg, t.offset * deg);
      break;
    case TargetShape::kChirp:
      std::snprintf(text, sizeof text, "+-%g deg chirps about %g deg, up to %g Hz",
                    t.amplitude * deg, t.offset * deg, t.chirp_end_hz);
      break;
    case TargetShape::kFile: return "the target of " + t.file;
  }
  return text;
}

std::string mismatch_text(const hmpc::hil::ForearmMismatch& m) {
  if (m.mass_scale == 1 && m.friction_scale == 1 && m.pam_time_constant_scale == 1)
    return "no mismatch";
  char text[128];
  std::snprintf(text, sizeof text, "mass x%g, friction x%g, valve time constant x%g", m.mass_scale,
                m.friction_scale, m.pam_time_constant_scale);
  return text;
}

// One strategy as a board runs it: the thesis's, or with our additions.
struct Variant {
  proto::Strategy kind = proto::Strategy::kTwoStage;
  bool offset_free = false;
  bool terminal_rate = false;  // the Two-stage's only
};

std::string label(const Variant& v) {
  return name(v.kind) + (v.terminal_rate ? "_terminal_rate" : "") +
         (v.offset_free ? "_offset_free" : "");
}

// Every strategy's variants in the tables' and plots' order: each as the thesis has it first.
// The terminal rate modes apply to the Two-stage; every other strategy runs once, as the
// thesis has it, whatever the mode (else --terminal-rate on would leave them out).
std::vector<Variant> variants(const Options& o) {
  const std::vector<bool> thesis_only{false};
  std::vector<Variant> out;
  for (proto::Strategy s : o.strategies)
    for (bool terminal_rate : s == proto::Strategy::kTwoStage ? o.terminal_rate : thesis_only)
      for (bool offset_free : o.offset_free) out.push_back({s, offset_free, terminal_rate});
  return out;
}

struct Row {
  std::string strategy;  // label(variant)
  double frequency = 0, w_v = 0;
  long trial = 0;
  HilRunResult r;
  Variant variant;
};

std::vector<std::string> labels(const Options& o) {
  std::vector<std::string> out;
  for (const Variant& v : variants(o)) out.push_back(label(v));
  return out;
}

struct Stats {
  double mean = 0, stddev = 0;
};
Stats stats(const std::vector<double>& v) {
  Stats s;
  for (double x : v) s.mean += x / double(v.size());
  for (double x : v) s.stddev += (x - s.mean) * (x - s.mean);
  s.stddev = v.size() > 1 ? std::sqrt(s.stddev / double(v.size() - 1)) : 0;
  return s;
}

std::string run_dir(const std::string& out, const std::string& strategy, double f, double w_v,
                    long trial) {
  std::ostringstream s;
  s << out << "/runs/" << strategy << "_" << f << "hz";
  if (w_v > 0) s << "_wv" << w_v;
  s << "_" << trial;
  return s.str();
}

// Groups of rows by (w_v, frequency, strategy) in the order they ran.
struct Group {
  std::string strategy;
  double frequency, w_v;
  std::vector<const Row*> rows;
};
std::vector<Group> groups(const std::vector<Row>& rows) {
  std::vector<Group> out;
  for (const Row& row : rows) {
    Group* g = nullptr;
    for (Group& candidate : out) {
      if (candidate.strategy == row.strategy && candidate.frequency == row.frequency &&
          candidate.w_v == row.w_v)
        g = &candidate;
    }
    if (!g) {
      out.push_back({row.strategy, row.frequency, row.w_v, {}});
      g = &out.back();
    }
    g->rows.push_back(&row);
  }
  return out;
}

template <class Get>
Stats group_stats(const Group& g, Get get) {
  std::vector<double> v;
  for (const Row* r : g.rows) v.push_back(get(r->r));
  return stats(v);
}

void write_tables(const std::string& out, const std::vector<Row>& rows, const Options& o) {
  std::ofstream csv(out + "/hil_runs.csv");
  csv << "strategy,frequency_hz,w_v,trial,accumulated_cost,rms_error_rad,solve_time_max_ms,"
         "solve_time_median_ms,deadline_misses,mean_abs_pam_torque_Nm,mean_abs_motor_torque_Nm,"
         "motor_share,theta_min_rad,theta_max_rad,within_stops,plant_real_time_factor\n";
  for (const Row& row : rows) {
    const HilRunResult& r = row.r;
    csv << row.strategy << "," << row.frequency << "," << row.w_v << "," << row.trial << ","
        << r.accumulated_cost << "," << r.rms_error << "," << r.solve_time_max_us / 1e3 << ","
        << r.solve_time_median_us / 1e3 << "," << r.deadline_misses << "," << r.mean_abs_pam_torque
        << "," << r.mean_abs_motor_torque << "," << r.motor_share() << "," << r.theta_min << ","
        << r.theta_max << "," << r.within_stops << "," << r.number(r.plant, "real_time_factor")
        << "\n";
  }

  std::ostringstream md;
  md << "# Forearm HIL over CAN: " << o.trials << " trial(s) of " << o.duration_s << " s per cell, "
     << target_text(o.target) << "\n\n"
     << "Board: hmpc-forearm-board, lock-step, compute time of the STM32H743 (Cortex-M7, 400 MHz)"
        " charged per solve. Plant: Simbody, "
     << mismatch_text(o.mismatch) << ", sensor noise x" << o.noise
     << ". Mean +- standard deviation over trials.\n\n"
     << "| f (Hz) | w_v | strategy | accumulated cost (Eq. 3.3) | RMS error (deg) | max solve (ms)"
        " | median solve (ms) | deadline misses | motor share of torque |\n"
     << "|---|---|---|---|---|---|---|---|---|\n";
  char line[512];
  for (const Group& g : groups(rows)) {
    const Stats cost = group_stats(g, [](const HilRunResult& r) { return r.accumulated_cost; });
    const Stats err =
        group_stats(g, [](const HilRunResult& r) { return r.rms_error * 180 / M_PI; });
    const Stats max_solve =
        group_stats(g, [](const HilRunResult& r) { return r.solve_time_max_us / 1e3; });
    const Stats median_solve =
        group_stats(g, [](const HilRunResult& r) { return r.solve_time_median_us / 1e3; });
    const Stats misses = group_stats(g, [](const HilRunResult& r) { return r.deadline_misses; });
    const Stats share = group_stats(g, [](const HilRunResult& r) { return r.motor_share(); });
    std::snprintf(
        line, sizeof line,
        "| %.2f | %g | %s | %.1f +- %.1f | %.3f +- %.3f | %.2f | %.2f | %.0f | %.1f %% |\n",
        g.frequency, g.w_v > 0 ? g.w_v : 0.002, g.strategy.c_str(), cost.mean, cost.stddev,
        err.mean, err.stddev, max_solve.mean, median_solve.mean, misses.mean, 100 * share.mean);
    md << line;
  }
  if (o.target.shape == hmpc::trajectory::TargetShape::kSine) {
    // What the plant's actuators allow at all, so that a large error reads against it.
    const hmpc::forearm::Parameters<double> plant =
        hmpc::hil::with_mismatch(hmpc::forearm::Parameters<double>{}, o.mismatch);
    md << "\nThe plant's actuator limit (first-harmonic bound, forearm_tracking_limit.hpp): ";
    for (std::size_t i = 0; i < o.frequencies.size(); ++i) {
      const hmpc::forearm::TrackingLimit l = hmpc::forearm::tracking_limit(
          plant, o.frequencies[i], o.target.amplitude, o.target.offset);
      std::snprintf(line, sizeof line, "%s%.2f Hz: +-%.1f deg, RMS error at least %.2f deg",
                    i ? "; " : "", o.frequencies[i], l.max_amplitude * 180 / M_PI,
                    l.rms_error_floor * 180 / M_PI);
      md << line;
    }
    md << ".\n";
  }
  double hil_load = 0, robot_load = 0, rtf = 0;
  for (const Row& row : rows) {
    hil_load += row.r.number(row.r.host, "bus_load_hil_1mbit") / double(rows.size());
    robot_load += row.r.number(row.r.host, "bus_load_robot_1mbit") / double(rows.size());
    rtf += row.r.number(row.r.plant, "real_time_factor") / double(rows.size());
  }
  std::snprintf(line, sizeof line,
                "\nCAN bus load measured by the host, at 1 Mbit/s with worst-case bit stuffing: "
                "%.1f %% in this HIL (with Sensor, ActuatorCommand and Sync frames), %.1f %% for "
                "the host-board traffic a robot has. Lock-step speed: %.2f x real time (mean "
                "over runs).\n",
                100 * hil_load, 100 * robot_load, rtf);
  md << line;
  std::ofstream(out + "/hil_summary.md") << md.str();
  std::printf("%s", md.str().c_str());
}

// Bars of one figure per strategy (rows) and frequency (columns) with error bars.
void write_bar_data(const std::string& path, const std::vector<Row>& rows, double w_v,
                    double (*get)(const HilRunResult&)) {
  std::ofstream data(path);
  data << "# strategy mean stddev per frequency\n";
  for (const Group& g : groups(rows)) {
    if (g.w_v != w_v) continue;
    const Stats s = group_stats(g, get);
    data << g.strategy << " " << g.frequency << " " << s.mean << " " << s.stddev << "\n";
  }
}

bool plot(const std::string& out, const std::vector<Row>& rows, const Options& o) {
  // A run's target in a title: "1 Hz sine", or the shape alone where no frequency applies.
  const auto target_label = [&](double f) {
    std::ostringstream label;
    if (f > 0) label << f << " Hz ";
    label << hmpc::trajectory::shape_name(o.target.shape);
    return label.str();
  };
  write_bar_data(out + "/hil_cost.dat", rows, 0,
                 [](const HilRunResult& r) { return r.accumulated_cost; });
  write_bar_data(out + "/hil_error.dat", rows, 0,
                 [](const HilRunResult& r) { return r.rms_error * 180 / M_PI; });
  write_bar_data(out + "/hil_solve.dat", rows, 0,
                 [](const HilRunResult& r) { return r.solve_time_max_us / 1e3; });
  std::ostringstream gp;
  gp << "set terminal pngcairo size 1000,600 noenhanced\nset datafile separator ' '\n"
        "set style data histograms\nset grid ytics\nset key outside right\n";
  // Bars: one cluster per frequency, one bar per strategy; error bars from the trials.
  const auto bars = [&](const char* file, const char* png, const char* title, const char* ylabel,
                        bool limit_line) {
    gp << "set output '" << out << "/" << png << "'\nset title '" << title << "'\nset ylabel '"
       << ylabel
       << "'\nset xlabel 'target'\nset boxwidth 0.12\n"
          "set style fill solid 0.6\nset yrange [0:*]\nset xrange [-0.5:"
       << o.frequencies.size() - 0.5 << "]\n"
       << "set xtics (";
    for (std::size_t i = 0; i < o.frequencies.size(); ++i)
      gp << (i ? ", " : "") << "'" << target_label(o.frequencies[i]) << "' " << i;
    gp << ")\nplot ";
    const std::vector<std::string> names = labels(o);
    for (std::size_t s = 0; s < names.size(); ++s) {
      const std::string& n = names[s];
      const double shift = (double(s) - 0.5 * double(names.size() - 1)) * 0.13;
      gp << (s ? ", " : "") << "'" << out << "/" << file << "' using ((";
      for (std::size_t i = 0; i < o.frequencies.size(); ++i)
        gp << "abs($2-" << o.frequencies[i] << ")<1e-9?" << i << ":";
      // A line type per variant: the error bars between boxes would otherwise take every other
      // one, and colours would repeat from the fifth variant on.
      gp << "-9)+" << shift << "):(strcol(1) eq '" << n << "' ? $3 : 1/0):(0.06) with boxes lt "
         << s + 1 << " title '" << n << "', '' using ((";
      for (std::size_t i = 0; i < o.frequencies.size(); ++i)
        gp << "abs($2-" << o.frequencies[i] << ")<1e-9?" << i << ":";
      gp << "-9)+" << shift << "):(strcol(1) eq '" << n
         << "' ? $3 : 1/0):4 with yerrorbars lc 'black' pt 0 notitle";
    }
    if (limit_line) gp << ", 4 with lines dt 2 lc 'black' title '4 ms control period'";
    gp << "\nunset xrange\nunset xtics\nset xtics\nset autoscale y\n";
  };
  bars("hil_cost.dat", "hil_cost.png", "Accumulated cost over the run (Eq. 3.3), cf. Fig. 3.3b",
       "accumulated cost", false);
  bars("hil_error.dat", "hil_error.png", "RMS tracking error, cf. Fig. 3.6", "RMS error (deg)",
       false);
  bars("hil_solve.dat", "hil_solve_time.png",
       "Max solve time charged on the Cortex-M7 (400 MHz), cf. Fig. 3.3a", "max solve time (ms)",
       true);
  // Joint angle vs target at each frequency, trial 1 of Fine 4 ms, Coarse 20 ms and Two-stage.
  for (double f : o.frequencies) {
    std::ostringstream png;
    png << out << "/hil_angle_" << f << "hz.png";
    gp << "set output '" << png.str() << "'\nset datafile separator ','\nset title 'Joint angle, "
       << target_label(f)
       << " target, trial 1 (cf. Fig. 3.5)'\nset xlabel 'time (s)'\nset ylabel "
          "'angle (deg)'\nplot ";
    bool first = true;
    for (const std::string& s : labels(o)) {
      if (s.rfind("fine_4ms", 0) != 0 && s.rfind("coarse_20ms", 0) != 0 &&
          s.rfind("two_stage", 0) != 0)
        continue;
      const std::string dir = run_dir(out, s, f, 0, 1);
      if (!std::filesystem::exists(dir + "/host.csv")) continue;
      if (first) {
        gp << "'" << dir
           << "/host.csv' every ::1 using 1:($6*180/pi) with lines dt 2 lw 2 "
              "title 'target', ";
      }
      gp << "'" << dir << "/plant.csv' every ::1 using 1:($2*180/pi) with lines title '" << s
         << "', ";
      first = false;
    }
    gp << "1/0 notitle\n";
  }
  // Torques of the Two-stage run at the highest frequency.
  const double f_max = *std::max_element(o.frequencies.begin(), o.frequencies.end());
  const std::string two_stage = run_dir(
      out, label({proto::Strategy::kTwoStage, o.offset_free.back(), o.terminal_rate.back()}), f_max,
      0, 1);
  if (std::filesystem::exists(two_stage + "/plant.csv")) {
    gp << "set output '" << out
       << "/hil_torques.png'\nset datafile separator ','\n"
          "set title 'Two-stage, "
       << target_label(f_max)
       << ": PAM and motor torque (cf. Fig. 3.9)'\n"
          "set xlabel 'time (s)'\nset ylabel 'torque (N m)'\nplot '"
       << two_stage
       << "/plant.csv' every ::1 using 1:7 with lines title 'PAM', '' every ::1 using 1:8 with "
          "lines title 'motor'\n";
  }
  if (o.weight_sweep) {
    // One block per strategy, so that gnuplot joins each strategy's points.
    std::ofstream data(out + "/hil_weight_sweep.dat");
    for (const char* strategy : {"fine_4ms", "coarse_20ms", "two_stage"}) {
      for (const Group& g : groups(rows)) {
        if (g.w_v <= 0 || g.strategy != strategy) continue;
        const Stats s = group_stats(g, [](const HilRunResult& r) { return r.accumulated_cost; });
        data << g.strategy << " " << g.w_v << " " << s.mean << " " << s.stddev << "\n";
      }
    }
    gp << "set output '" << out
       << "/hil_weight_sweep.png'\nset datafile separator ' '\n"
          "set title 'Accumulated cost at 1 Hz for three voltage weights w_v (cf. Fig. 3.4)'\n"
          "set xlabel 'w_v'\nset logscale x\nset ylabel 'accumulated cost'\nplot ";
    const char* sweep[] = {"fine_4ms", "coarse_20ms", "two_stage"};
    for (int i = 0; i < 3; ++i) {
      gp << (i ? ", " : "") << "'" << out << "/hil_weight_sweep.dat' using 2:(strcol(1) eq '"
         << sweep[i] << "' ? $3 : 1/0):4 with yerrorlines title '" << sweep[i] << "'";
    }
    gp << "\nunset logscale x\n";
  }
  const std::string script = out + "/hil_plots.gp";
  std::ofstream(script) << gp.str();
  return std::system(("gnuplot '" + script + "' 2> '" + out + "/hil_plots.log'").c_str()) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  std::string error;
  const auto outcome = parse(argc, argv, o, error);
  if (outcome != hmpc::cli::ParseOutcome::kRun) {
    return hmpc::cli::exit_status(outcome, kProgram, error, print_usage);
  }
  const hmpc::hil::HilPrograms programs = hmpc::hil::HilPrograms::built();
  // Every run to make, in the order of the tables; each gets its row slot.
  std::vector<Row> rows;
  for (double f : o.frequencies)
    for (const Variant& v : variants(o))
      for (long trial = 1; trial <= o.trials; ++trial)
        rows.push_back({label(v), f, 0, trial, {}, v});
  if (o.weight_sweep) {
    for (double w_v : kSweepWeights)
      for (proto::Strategy s :
           {proto::Strategy::kFine4ms, proto::Strategy::kCoarse20ms, proto::Strategy::kTwoStage})
        for (long trial = 1; trial <= o.trials; ++trial)
          rows.push_back({name(s), 1.0, w_v, trial, {}, Variant{s}});
  }
  // --jobs workers, each with its own board node id on the bus (the protocol's node filter
  // keeps their frames apart), take the runs in order.
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex print;
  const auto worker = [&](proto::NodeId node) {
    for (std::size_t i = next++; i < rows.size() && !failed; i = next++) {
      Row& row = rows[i];
      HilRunSpec spec;
      spec.strategy = row.variant.kind;
      if (row.variant.offset_free) spec.board_args.push_back("--offset-free");
      if (row.variant.terminal_rate) spec.board_args.push_back("--terminal-rate");
      spec.node = node;
      spec.target = o.target;
      if (row.frequency > 0) spec.target.frequency_hz = row.frequency;
      spec.run_for_s = o.duration_s;
      spec.noise_scale = o.noise;
      spec.seed = std::uint64_t(row.trial);
      spec.w_v = row.w_v;
      spec.mismatch = o.mismatch;
      spec.directory = run_dir(o.out, row.strategy, row.frequency, row.w_v, row.trial);
      row.r = hmpc::hil::run_hil(spec, programs);
      const std::lock_guard<std::mutex> lock(print);
      if (!row.r.ok) {
        std::fprintf(stderr, "%s: %s at %g Hz, trial %ld failed: %s\n", kProgram,
                     row.strategy.c_str(), row.frequency, row.trial, row.r.error.c_str());
        failed = true;
        return;
      }
      std::printf(
          "%s: %-12s %5.2f Hz w_v %-6g trial %ld: cost %8.1f  RMS %.3f deg  max solve "
          "%.2f ms  misses %.0f  motor share %.1f %%  plant RTF %.2f\n",
          kProgram, row.strategy.c_str(), row.frequency, row.w_v > 0 ? row.w_v : 0.002, row.trial,
          row.r.accumulated_cost, row.r.rms_error * 180 / M_PI, row.r.solve_time_max_us / 1e3,
          row.r.deadline_misses, 100 * row.r.motor_share(),
          row.r.number(row.r.plant, "real_time_factor"));
      std::fflush(stdout);
    }
  };
  std::vector<std::thread> workers;
  for (long j = 0; j < o.jobs; ++j) workers.emplace_back(worker, proto::NodeId(j));
  for (std::thread& w : workers) w.join();
  if (failed) return 1;
  write_tables(o.out, rows, o);
  if (!plot(o.out, rows, o)) {
    std::fprintf(stderr,
                 "%s: gnuplot failed (see %s/hil_plots.log); install it with "
                 "toolchains/setup-debian.sh\n",
                 kProgram, o.out.c_str());
    return 1;
  }
  std::printf("%s: wrote %s/hil_runs.csv, hil_summary.md and the hil_*.png plots\n", kProgram,
              o.out.c_str());
  return 0;
}
