// Every input in tests/fuzz/regressions (crashes the fuzzer once found) and tests/fuzz/corpus
// goes through the fuzzed entry point in the ordinary test run: each must end in a clear error
// or a valid study, never anything else.
#include "fuzz_target.hpp"

#include <boost/filesystem.hpp>
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

namespace fs = boost::filesystem;

TEST(FuzzRegression, EveryKnownInputEndsInAnErrorOrAValidStudy) {
  int inputs = 0;
  for (const char* dir : {"tests/fuzz/regressions", "tests/fuzz/corpus", "problems"}) {
    const fs::path d = fs::path(HAPSYN_SOURCE_DIR) / dir;
    if (!fs::is_directory(d)) continue;
    for (const auto& entry : fs::directory_iterator(d)) {
      if (!fs::is_regular_file(entry.path())) continue;
      std::ifstream in(entry.path().string(), std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      SCOPED_TRACE(entry.path().string());
      EXPECT_NO_THROW(hapsyn::fuzz::fuzz_one(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
      ++inputs;
    }
  }
  EXPECT_GT(inputs, 10);
}
