// Fuzz target for the readers of the files a user hands the host programs: motion files
// (humanoid/motion.hpp), IOC weights and demonstrations (ioc/files.hpp). The first input byte
// picks the reader, the rest is the file's text. Properties: a reader either throws its own
// error type (MotionFileError, IocFileError: file, line and what is wrong) or returns what it
// read; anything else (a crash, another exception) is a finding. What it returns is valid
// enough to write: written, read again and written again, the text is the same.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "hmpc/humanoid/motion.hpp"
#include "hmpc/ioc/files.hpp"

namespace {

[[noreturn]] void fail(const char* reader, const std::string& what) {
  std::fprintf(stderr, "files fuzz (%s): %s\n", reader, what.c_str());
  std::abort();
}

template <class Error, class Read, class Write>
void check(const char* reader, const std::string& text, Read&& read, Write&& write) {
  std::istringstream in(text);
  try {
    const auto value = read(in);
    std::ostringstream once;
    write(once, value);
    std::istringstream again(once.str());
    std::ostringstream twice;
    write(twice, read(again));
    if (once.str() != twice.str()) fail(reader, "written, read and written again, it differs");
  } catch (const Error&) {
    // Rejected with file, line and reason: what a reader must do with bad input.
  } catch (const std::exception& e) {
    fail(reader, std::string("unexpected exception: ") + e.what());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 3) {
    case 0:
      check<hmpc::humanoid::MotionFileError>(
          "motion", text, [](std::istream& in) { return hmpc::humanoid::parse_motion(in, "fuzz"); },
          [](std::ostream& out, const hmpc::humanoid::Motion& m) {
            hmpc::humanoid::write_motion(out, m, "");
          });
      break;
    case 1:
      check<hmpc::ioc::IocFileError>(
          "weights", text, [](std::istream& in) { return hmpc::ioc::parse_weights(in, "fuzz"); },
          [](std::ostream& out, const hmpc::ioc::Weights& w) { hmpc::ioc::write_weights(out, w); });
      break;
    default:
      check<hmpc::ioc::IocFileError>(
          "demonstrations", text,
          [](std::istream& in) { return hmpc::ioc::parse_demonstrations(in, "fuzz"); },
          [](std::ostream& out, const std::vector<hmpc::ioc::Demonstration>& d) {
            hmpc::ioc::write_demonstrations(out, d);
          });
      break;
  }
  return 0;
}

#ifdef HMPC_FUZZ_REPLAY
#include <filesystem>
#include <fstream>

#include "fuzz_replay.hpp"

// Seeds: every shipped motion file, and weights and demonstrations files from the writers.
int main(int argc, char** argv) {
  using hmpc::fuzz::Bytes;
  std::vector<Bytes> seeds;
  const auto add = [&](std::uint8_t reader, const std::string& text) {
    Bytes b{reader};
    b.insert(b.end(), text.begin(), text.end());
    seeds.push_back(b);
  };
  for (const char* dir : {HMPC_HUMANOID_MOTIONS, HMPC_IOC_DEMONSTRATORS}) {
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
      std::ifstream in(entry.path());
      std::stringstream text;
      text << in.rdbuf();
      add(0, text.str());
    }
  }
  std::ostringstream weights;
  hmpc::ioc::write_weights(weights, hmpc::ioc::initial_weights(), "initial weights");
  add(1, weights.str());
  hmpc::ioc::Demonstration d;
  hmpc::humanoid::StateVector x = hmpc::humanoid::StateVector::Zero();
  x[2] = 0.85;
  x[3] = 1.0;  // unit quaternion
  d.states = {x, x};
  d.inputs = {hmpc::humanoid::JointVector::Constant(1.5)};
  std::ostringstream demonstrations;
  hmpc::ioc::write_demonstrations(demonstrations, {d, d});
  add(2, demonstrations.str());
  return hmpc::fuzz::replay(argc, argv, "files_fuzz_replay", seeds, 200, 200);
}
#endif
