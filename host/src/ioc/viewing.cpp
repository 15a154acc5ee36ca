#include "hmpc/ioc/viewing.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "hmpc/humanoid/viewing.hpp"

namespace hmpc::ioc {

bool write_comparison(const std::string& dir, const std::string& title,
                      const std::vector<WeightSet>& sets, std::string& error) {
  namespace fs = std::filesystem;
  const fs::path base(dir);
  std::error_code ec;
  fs::create_directories(base, ec);
  {
    std::ofstream dat(base / "weights.dat");
    dat << "# weight";
    for (const WeightSet& set : sets) dat << ' ' << set.name;
    dat << '\n';
    for (int k = 0; k < kWeightCount; ++k) {
      dat << kWeightNames[k];
      for (const WeightSet& set : sets) dat << ' ' << set.weights[k];
      dat << '\n';
    }
    if (!dat.flush()) {
      error = "cannot write " + (base / "weights.dat").string();
      return false;
    }
  }
  const int A = 0;  // the biped's columns
  const int target = humanoid::kTargetHeightColumn<A>, q = humanoid::kQuaternionColumn;
  const std::string pitch = "(asin(2*(column(" + std::to_string(q) + ")*column(" +
                            std::to_string(q + 2) + ")-column(" + std::to_string(q + 3) +
                            ")*column(" + std::to_string(q + 1) + "))))";
  // One panel: `run` (a using-expression for a run) against the target column `goal`.
  const auto panel = [&](const std::string& label, const std::string& run, int goal) {
    std::string plot = "set ylabel '" + label + "'\nplot ";
    bool first = true;
    for (const WeightSet& set : sets) {
      if (!set.has_run) continue;
      const std::string file = "'" + set.name + "/trajectory.csv'";
      if (first)
        plot += file + " using 1:" + std::to_string(goal) +
                " with steps dt 2 lc 'black' title 'target', ";
      plot += file;
      plot += " using 1:" + run;
      plot += " with lines lw 2 title '" + set.name + "', ";
      first = false;
    }
    return plot.substr(0, plot.size() - 2) + "\n";
  };
  const fs::path script = base / "compare.gp";
  {
    std::ofstream gp(script);
    gp << "# gnuplot compare.gp (in this directory) redraws the pictures\n"
       << "set terminal pngcairo size 1000,480 noenhanced\nset output 'weights.png'\n"
       << "set title '" << title << ": weights (Eq. 4.31)'\n"
       << "set style data histograms\nset style histogram clustered gap 1\nset style fill solid "
          "0.8 border -1\n"
       << "set logscale y\nset format y '%g'\nset ylabel 'weight'\nset key top left\nset xtics "
          "rotate by -30\n"
       << "plot ";
    for (std::size_t i = 0; i < sets.size(); ++i) {
      gp << (i == 0 ? "" : ", ") << "'weights.dat' using " << i + 2 << (i == 0 ? ":xtic(1)" : "")
         << " title '" << sets[i].name << "'";
    }
    gp << "\nreset\nset terminal pngcairo size 900,1000 noenhanced\nset output 'compare.png'\n"
       << "set datafile separator ','\nset key outside top center horizontal\n"
       << "set multiplot layout 4,1 title '" << title << ": base point against the targets'\n"
       << panel("height [m]", std::to_string(humanoid::kHeightColumn), target)
       << panel("pitch [rad]", pitch, target + 5)
       << panel("v_x [m/s]", std::to_string(humanoid::kVelocityColumn), target + 1)
       << "set xlabel 'time [s]'\n"
       << panel("v_z [m/s]", std::to_string(humanoid::kVelocityColumn + 2), target + 3)
       << "unset multiplot\n";
    if (!gp.flush()) {
      error = "cannot write " + script.string();
      return false;
    }
  }
  const std::string command = "cd '" + dir + "' && gnuplot compare.gp 2> gnuplot.log";
  if (std::system(command.c_str()) != 0) {
    error = "gnuplot failed (see " + (base / "gnuplot.log").string() +
            "); install it with toolchains/setup-debian.sh";
    return false;
  }
  return true;
}

}  // namespace hmpc::ioc
