// Command lines of the Linux programs (board, plant node, host controller): options declared
// once with their ranges, values parsed as whole strings, so "5x", "", "nan" and "1e400" are
// errors naming the option, never a silent 0 or inf. Start-up only (it allocates).
#pragma once

#include <net/if.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <string>

namespace hmpc::cli {

inline bool parse_number(const std::string& text, double lo, double hi, double& out) {
  if (text.empty()) return false;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (*end != '\0' || !std::isfinite(value) || value < lo || value > hi) return false;
  out = value;
  return true;
}

inline bool parse_integer(const std::string& text, long lo, long hi, long& out) {
  if (text.empty()) return false;
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (*end != '\0' || value < lo || value > hi) return false;
  out = value;
  return true;
}

inline std::string bad_value(const std::string& name, const std::string& what,
                             const std::string& text) {
  return name + " must be " + what + ", got '" + text + "'";
}

// The longest --duration of the Linux programs: longer than any run a test or an experiment
// needs, short enough that a tick count (uint32 at 1 kHz) cannot wrap.
inline constexpr double kMaxDurationS = 1e6;

enum class ParseOutcome { kRun, kHelp, kError };

// What main() makes of a parse: kRun to go on; otherwise the program's exit status, after the
// usage (--help: 0, on stdout) or the error and the usage (2, on stderr).
inline int exit_status(ParseOutcome outcome, const char* program, const std::string& error,
                       void (*print_usage)(std::FILE*)) {
  if (outcome == ParseOutcome::kHelp) {
    print_usage(stdout);
    return 0;
  }
  std::fprintf(stderr, "%s: %s\n", program, error.c_str());
  print_usage(stderr);
  return 2;
}

class OptionParser {
 public:
  // Sets `target` when the option is present.
  void flag(const std::string& name, bool& target) { flags_[name] = &target; }
  // A number in [lo, hi], stored times `scale` (e.g. 0.01 for a percentage into a fraction).
  void number(const std::string& name, double lo, double hi, const std::string& what,
              double& target, double scale = 1) {
    valued_[name] = [=, &target](const std::string& v, std::string& error) {
      double value = 0;
      if (!parse_number(v, lo, hi, value)) {
        error = bad_value(name, what, v);
        return false;
      }
      target = value * scale;
      return true;
    };
  }
  template <typename Integer>
  void integer(const std::string& name, long lo, long hi, Integer& target) {
    valued_[name] = [=, &target](const std::string& v, std::string& error) {
      long value = 0;
      if (!parse_integer(v, lo, hi, value)) {
        error =
            bad_value(name, "an integer in " + std::to_string(lo) + ".." + std::to_string(hi), v);
        return false;
      }
      target = Integer(value);
      return true;
    };
  }
  // A network interface name (can0, vcan1): 1 to IFNAMSIZ - 1 characters, as the kernel takes.
  void interface(const std::string& name, std::string& target) {
    text(name, [name, &target](const std::string& v) -> std::string {
      if (v.empty() || v.size() >= IFNAMSIZ) {
        return bad_value(name, "a name of 1.." + std::to_string(IFNAMSIZ - 1) + " characters", v);
      }
      target = v;
      return {};
    });
  }
  // Any other value: `accept` stores it or says what is wrong (a non-empty message).
  void text(const std::string& name, std::function<std::string(const std::string&)> accept) {
    valued_[name] = [accept = std::move(accept)](const std::string& v, std::string& error) {
      error = accept(v);
      return error.empty();
    };
  }

  ParseOutcome parse(int argc, char** argv, std::string& error) const {
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "-h" || arg == "--help") return ParseOutcome::kHelp;
      const auto flag = flags_.find(arg);
      if (flag != flags_.end()) {
        *flag->second = true;
        continue;
      }
      const auto option = valued_.find(arg);
      if (option == valued_.end()) {
        error = "unknown option '" + arg + "'";
        return ParseOutcome::kError;
      }
      if (i + 1 >= argc) {
        error = arg + " needs a value";
        return ParseOutcome::kError;
      }
      if (!option->second(argv[++i], error)) return ParseOutcome::kError;
    }
    return ParseOutcome::kRun;
  }

 private:
  std::map<std::string, bool*> flags_;
  std::map<std::string, std::function<bool(const std::string&, std::string&)>> valued_;
};

}  // namespace hmpc::cli
