// IOC's files: learned weights and demonstrations, versioned text that a person can read.
//
// Weights (`*.weights`; UTF-8 text, one setting per line):
//   - '#' starts a comment; blank lines are ignored.
//   - The first other line is the version line, exactly `hmpc-ioc-weights 1`.
//   - Then `key = value` for each of the 13 weights of Eq. 4.31, keyed as in motion files
//     (weights.hpp's kWeightNames: w_HAA ... w_vz), each exactly once, finite and > 0.
//
// Demonstrations (`*.csv`): the version line `hmpc-ioc-demonstrations 1`, then the header
//   demo,time,x0,...,x28,u0,...,u7
// then one row per state: the demonstration's number (0, 1, ... in order), the state's time in
// the motion's schedule [s] (rows of one demonstration 30 ms apart, the coarse step), the
// state x = (q, v) of model.hpp (29 numbers; the quaternion q3..q6 of unit norm), and the
// inputs held from it to the next state [N m]; a demonstration's last row has its inputs
// empty. Every number finite; a demonstration has at least one input.
//
// Reading checks everything above and throws IocFileError naming the file, the line and what
// is wrong; nothing half-read is returned.
#pragma once

#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

#include "hmpc/ioc/local_ioc.hpp"

namespace hmpc::ioc {

class IocFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `comment` (may be empty; one line per '\n') is written as '#' lines after the version line.
void write_weights(std::ostream& out, const Weights& w, const std::string& comment = "");
Weights parse_weights(std::istream& in, const std::string& source);
Weights load_weights(const std::string& path);

void write_demonstrations(std::ostream& out, const std::vector<Demonstration>& demonstrations);
std::vector<Demonstration> parse_demonstrations(std::istream& in, const std::string& source);
std::vector<Demonstration> load_demonstrations(const std::string& path);

}  // namespace hmpc::ioc
