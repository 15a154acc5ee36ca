// A program run as a child process with its stdout and stderr in files, for the HIL runs and
// tests: start, wait for a line of output, wait for the exit with a timeout, stop; and the
// key=value summary line the programs print at exit.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace hmpc::platform {

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The key=value pairs of the last "<program>: summary ..." line in a program's output; a value
// in double quotes (key="a reason with spaces") is taken whole, without its quotes.
inline std::map<std::string, std::string> parse_summary(const std::string& text) {
  std::map<std::string, std::string> out;
  const std::size_t at = text.rfind(": summary ");
  if (at == std::string::npos) return out;
  std::istringstream words(text.substr(at + 10, text.find('\n', at) - at - 10));
  std::string word;
  while (words >> word) {
    const std::size_t eq = word.find('=');
    if (eq == std::string::npos) continue;
    std::string value = word.substr(eq + 1);
    if (!value.empty() && value.front() == '"') {
      std::string more;
      while ((value.size() < 2 || value.back() != '"') && words >> more) value += " " + more;
      value = value.substr(1, value.size() >= 2 && value.back() == '"' ? value.size() - 2 : 0);
    }
    out[word.substr(0, eq)] = value;
  }
  return out;
}

// A summary's number under `key`; NaN when it has none.
inline double summary_number(const std::map<std::string, std::string>& summary,
                             const std::string& key) {
  const auto it = summary.find(key);
  return it == summary.end() ? std::nan("") : std::strtod(it->second.c_str(), nullptr);
}

// A program with its stdout in `output` and its stderr in `output`.err.
class Child {
 public:
  using Clock = std::chrono::steady_clock;

  Child() = default;
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }

  bool start(const std::string& program, const std::vector<std::string>& args,
             const std::string& output, std::string& error) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_addopen(&actions, 2, (output + ".err").c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(program.c_str()));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const int rc = posix_spawn(&pid_, program.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    output_ = output;
    if (rc != 0) {
      pid_ = -1;
      error = "cannot start " + program + ": " + std::strerror(rc);
      return false;
    }
    return true;
  }

  // Waits until the program's stdout contains `text`, or it exits, or the timeout.
  bool await_output(const std::string& text, double timeout_s) {
    const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (Clock::now() < end) {
      if (read_file(output_).find(text) != std::string::npos) return true;
      if (exited()) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }

  // Waits for the exit; -1 on timeout (the program is still running).
  int wait(double timeout_s) {
    const auto end = Clock::now() + std::chrono::duration<double>(timeout_s);
    while (Clock::now() < end) {
      if (exited()) return status_;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }

  int stop(double timeout_s) {
    signal(SIGTERM);
    return wait(timeout_s);
  }

  // Sends a signal while the program runs (e.g. SIGSTOP: a process that hangs).
  void signal(int number) const {
    if (pid_ > 0) ::kill(pid_, number);
  }

  std::string output() const { return read_file(output_); }
  std::string errors() const { return read_file(output_ + ".err"); }

 private:
  bool exited() {
    if (pid_ <= 0) return true;
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) != pid_) return false;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    pid_ = -1;
    return true;
  }

  pid_t pid_ = -1;
  int status_ = -1;
  std::string output_;
};

}  // namespace hmpc::platform
