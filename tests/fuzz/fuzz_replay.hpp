// The replay side of a fuzz target: with HMPC_FUZZ_REPLAY a target is a plain program (any
// compiler) that runs its LLVMFuzzerTestOneInput on a fixed-seed corpus, so every CI run checks
// the target's properties; with clang and HMPC_BUILD_FUZZERS it is a libFuzzer binary instead.
// A target defines replay_corpus(): the seed inputs (valid ones from the project's own writers
// or files) that mutate() then damages the way a fuzzer's first mutations would.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace hmpc::fuzz {

using Bytes = std::vector<std::uint8_t>;

inline Bytes bytes_of(const std::string& text) { return Bytes(text.begin(), text.end()); }

// 1..4 of: flip a bit, overwrite a byte, delete a run, duplicate a run, insert random bytes.
inline Bytes mutate(Bytes in, std::mt19937_64& rng) {
  const int edits = 1 + int(rng() % 4);
  for (int e = 0; e < edits; ++e) {
    const std::size_t at = in.empty() ? 0 : rng() % in.size();
    const std::size_t run = 1 + rng() % 16;
    switch (rng() % 5) {
      case 0:
        if (!in.empty()) in[at] = std::uint8_t(in[at] ^ (1u << (rng() % 8)));
        break;
      case 1:
        if (!in.empty()) in[at] = std::uint8_t(rng());
        break;
      case 2:
        in.erase(in.begin() + long(at), in.begin() + long(std::min(in.size(), at + run)));
        break;
      case 3: {
        const Bytes copy(in.begin() + long(at), in.begin() + long(std::min(in.size(), at + run)));
        in.insert(in.begin() + long(at), copy.begin(), copy.end());
        break;
      }
      default:
        for (std::size_t i = 0; i < run; ++i) in.insert(in.begin() + long(at), std::uint8_t(rng()));
        break;
    }
  }
  return in;
}

// Runs every seed as it is, then `mutations` damaged copies of each, and random inputs. With
// the arguments `--write-corpus DIR` it writes the seeds to DIR instead, one file each: the
// starting corpus of the libFuzzer binary's bounded run.
inline int replay(int argc, char** argv, const char* name, const std::vector<Bytes>& seeds,
                  int mutations, int random_inputs) {
  if (argc == 3 && std::string(argv[1]) == "--write-corpus") {
    for (std::size_t i = 0; i < seeds.size(); ++i) {
      const std::string path = std::string(argv[2]) + "/seed-" + std::to_string(i);
      std::FILE* f = std::fopen(path.c_str(), "wb");
      if (f == nullptr || std::fwrite(seeds[i].data(), 1, seeds[i].size(), f) != seeds[i].size() ||
          std::fclose(f) != 0) {
        std::fprintf(stderr, "%s: cannot write %s\n", name, path.c_str());
        return 1;
      }
    }
    return 0;
  }
  if (argc != 1) {
    std::fprintf(stderr, "usage: %s [--write-corpus DIR]\n", name);
    return 2;
  }
  std::mt19937_64 rng(0x5eedf00dULL);
  std::size_t runs = 0;
  const auto run = [&](const Bytes& b) {
    LLVMFuzzerTestOneInput(b.data(), b.size());
    ++runs;
  };
  for (const Bytes& seed : seeds) {
    run(seed);
    for (int m = 0; m < mutations; ++m) run(mutate(seed, rng));
  }
  for (int n = 0; n < random_inputs; ++n) {
    Bytes b(rng() % 256);
    for (std::uint8_t& byte : b) byte = std::uint8_t(rng());
    run(b);
  }
  std::printf("%s: %zu seeds, %zu inputs replayed\n", name, seeds.size(), runs);
  return seeds.empty() ? 1 : 0;
}

}  // namespace hmpc::fuzz
