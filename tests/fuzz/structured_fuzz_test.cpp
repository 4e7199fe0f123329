// The structure-aware mutations of the fuzz target (fuzz_mutator.hpp), applied deterministically
// to every corpus input in the ordinary build: each mutant must end in hapsyn::Error or a valid
// study, never in another exception, a crash or a hang (ctest's timeout). A short, fixed-seed
// version of what scripts/test-sanitizers.sh runs under libFuzzer.
#include "fuzz_mutator.hpp"
#include "fuzz_target.hpp"

#include <boost/filesystem.hpp>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>

namespace fs = boost::filesystem;

TEST(StructuredFuzz, MutantsOfTheCorpusEndInAnErrorOrAValidStudy) {
  std::vector<std::string> inputs;
  for (const char* dir : {"tests/fuzz/corpus", "tests/fuzz/regressions"}) {
    const fs::path d = fs::path(HAPSYN_SOURCE_DIR) / dir;
    if (!fs::is_directory(d)) continue;
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(d)) {
      if (fs::is_regular_file(entry.path())) files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& f : files) {
      std::ifstream in(f.string(), std::ios::binary);
      inputs.emplace_back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    }
  }
  ASSERT_FALSE(inputs.empty());
  std::mt19937_64 rng(20);
  const int rounds = 400;
  for (int i = 0; i < rounds; ++i) {
    std::string input = inputs[static_cast<std::size_t>(i) % inputs.size()];
    // One to three structural mutations in a row, 100000 bytes at most (the fuzzer's -max_len).
    const int steps = 1 + static_cast<int>(rng() % 3);
    for (int k = 0; k < steps; ++k) hapsyn::fuzz::mutate_structure(input, 100000, rng);
    SCOPED_TRACE("mutant " + std::to_string(i) + ": " + input.substr(0, 200));
    // HAPSYN_FUZZ_VERBOSE=1: name each mutant before it runs (a crash ends the process, not the test).
    if (std::getenv("HAPSYN_FUZZ_VERBOSE")) std::cerr << "mutant " << i << " (" << input.size() << " bytes): " << input.substr(0, 120) << std::endl;
    EXPECT_NO_THROW(hapsyn::fuzz::fuzz_one(reinterpret_cast<const std::uint8_t*>(input.data()), input.size()));
  }
}
