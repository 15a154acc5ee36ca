// Pictures of `hmpc-ioc compare`, as the thesis's Figs. 4.3-4.5: weights.png, the weight sets
// as bars on a log scale (Fig. 4.3), and compare.png, each run's base height, pitch and
// velocity against the targets (Figs. 4.4-4.5 show the motions as frames: each run's
// filmstrip.png has those).
#pragma once

#include <string>
#include <vector>

#include "hmpc/ioc/weights.hpp"

namespace hmpc::ioc {

struct WeightSet {
  std::string name;  // also the run's directory under DIR (humanoid::write_run), if it has one
  Weights weights;
  bool has_run = false;
};

// Writes DIR/weights.dat, DIR/compare.gp and runs gnuplot for DIR/weights.png and, from the
// runs in DIR/<name>/trajectory.csv, DIR/compare.png. Returns false with the reason in `error`
// if a file cannot be written or gnuplot fails.
bool write_comparison(const std::string& dir, const std::string& title,
                      const std::vector<WeightSet>& sets, std::string& error);

}  // namespace hmpc::ioc
