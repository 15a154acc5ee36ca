// hmpc-sec24: the thesis's numerical example (Sec. 2.4) with all four MPCs, closed loop.
// Prints the comparison table (final states, accumulated cost, max/median solve time as in
// Fig. 2.5), writes the trajectories as CSV and plots them like Figs. 2.3/2.4.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "hmpc/host/sec24_scenario.hpp"

namespace {

void usage(std::FILE* out) {
  std::fprintf(out,
               "usage: hmpc-sec24 [--out DIR] [--trials N]\n"
               "  --out DIR    where to write sec24_trajectories.csv and the PNG plots "
               "(default: sec24)\n"
               "  --trials N   closed-loop runs per method for the timing statistics, 1..100 "
               "(default: 5, as in the thesis)\n");
}

struct Options {
  std::string out = "sec24";
  int trials = 5;
};

bool parse(int argc, char** argv, Options& options) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      usage(stdout);
      std::exit(0);
    }
    if (i + 1 >= argc) {
      std::fprintf(stderr, "hmpc-sec24: %s needs a value\n", arg.c_str());
      return false;
    }
    const std::string value = argv[++i];
    if (arg == "--out") {
      options.out = value;
    } else if (arg == "--trials") {
      char* end = nullptr;
      const long n = std::strtol(value.c_str(), &end, 10);
      if (end == value.c_str() || *end != '\0' || n < 1 || n > 100) {
        std::fprintf(stderr, "hmpc-sec24: --trials must be an integer in 1..100, got '%s'\n",
                     value.c_str());
        return false;
      }
      options.trials = static_cast<int>(n);
    } else {
      std::fprintf(stderr, "hmpc-sec24: unknown option '%s'\n", arg.c_str());
      return false;
    }
  }
  return true;
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}
double stddev(const std::vector<double>& v) {
  const double m = mean(v);
  double s = 0;
  for (double x : v) s += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(s / static_cast<double>(v.size() - 1)) : 0.0;
}

bool plot(const std::filesystem::path& dir, const std::filesystem::path& csv) {
  const auto script = dir / "sec24_plots.gp";
  std::ofstream gp(script);
  gp << "set datafile separator ','\n"
        "set terminal pngcairo size 900,560 font ',11'\n"
        "set key bottom right\nset grid\nset xlabel 'time [s]'\n"
        "methods = 'fine coarse slow-fast coarse-fast'\n"
        "titles = 'Fine Coarse Slow-Fast Coarse-Fast'\n"
        "sel(m, col) = (strcol(1) eq m) ? column(col) : NaN\n"
        "set output '"
     << (dir / "sec24_slow_state_y.png").string()
     << "'\n"
        "set title 'Slow state y (cf. thesis Fig. 2.3), y_d = 1.0'\nset ylabel 'y'\n"
        "plot for [i=1:4] '"
     << csv.string()
     << "' every ::1 using 2:(sel(word(methods,i),3)) "
        "with lines lw 2 title word(titles,i), 1.0 with lines dt 2 lc 'black' title 'y_d'\n"
        "set output '"
     << (dir / "sec24_fast_state_z.png").string()
     << "'\n"
        "set title 'Fast state z (cf. thesis Fig. 2.4), z_d = 2.0'\nset ylabel 'z'\n"
        "plot for [i=1:4] '"
     << csv.string()
     << "' every ::1 using 2:(sel(word(methods,i),4)) "
        "with lines lw 2 title word(titles,i), 2.0 with lines dt 2 lc 'black' title 'z_d'\n";
  gp.close();
  const std::string command = "gnuplot '" + script.string() + "'";
  return std::system(command.c_str()) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace hmpc::sec24;
  Options options;
  if (!parse(argc, argv, options)) {
    usage(stderr);
    return 2;
  }
  const std::filesystem::path dir(options.out);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    std::fprintf(stderr, "hmpc-sec24: cannot create '%s': %s\n", dir.c_str(), ec.message().c_str());
    return 1;
  }

  std::vector<RunResult> first_runs;
  std::printf(
      "Thesis Sec. 2.4, Eq. 2.37 (eps = 0.1), x0 = (0, 0), x_d = (1, 2), 0.4 s at 1 ms,"
      " iLQR cap 50, tol 1e-6; %d trial(s) per method\n\n",
      options.trials);
  std::printf("%-12s %8s %8s %12s %14s %14s %10s %9s\n", "method", "final y", "final z",
              "accum. cost", "max solve ms", "median ms", "mean iter", "unusable");
  for (Method method : kAllMethods) {
    std::vector<double> max_ms, median_ms;
    RunResult first;
    for (int trial = 0; trial < options.trials; ++trial) {
      RunResult r = run(method);
      max_ms.push_back(r.max_solve_seconds * 1e3);
      median_ms.push_back(r.median_solve_seconds * 1e3);
      if (trial == 0) first = std::move(r);
    }
    double iterations = 0;
    for (const auto& s : first.steps) iterations += s.iterations;
    iterations /= static_cast<double>(first.steps.size());
    std::printf("%-12s %8.4f %8.4f %12.5f %8.3f±%-5.3f %8.4f±%-5.4f %10.2f %9d\n",
                to_string(method), first.final_y, first.final_z, first.accumulated_cost,
                mean(max_ms), stddev(max_ms), mean(median_ms), stddev(median_ms), iterations,
                first.unusable_solves);
    first_runs.push_back(std::move(first));
  }
  std::printf(
      "\nsampling time 1.000 ms: a method is real-time when its max solve is below it"
      " (absolute times depend on this machine; compare the ratios)\n");

  const auto csv = dir / "sec24_trajectories.csv";
  write_trajectories_csv(first_runs, csv.string());
  std::printf("wrote %s\n", csv.c_str());
  if (!plot(dir, csv)) {
    std::fprintf(stderr,
                 "hmpc-sec24: gnuplot failed; install it with toolchains/setup-debian.sh\n");
    return 1;
  }
  std::printf("wrote %s and %s\n", (dir / "sec24_slow_state_y.png").c_str(),
              (dir / "sec24_fast_state_z.png").c_str());
  return 0;
}
