// libFuzzer target (HAPSYN_BUILD_FUZZERS=ON, clang): the problem loader and the --set parser.
// An input is zero or more lines "--set path=value" followed by a problem file (fuzz_target.hpp).
// Structure-aware: half of the mutations are libFuzzer's own (with tests/fuzz/problem.dict), the
// other half fuzz_mutator.hpp's (deep nesting, huge numbers, invalid UTF-8, duplicate keys, long
// strings, hostile --set lines). Needs -max_len large enough for deep nesting (100000: see
// tests/fuzz/CMakeLists.txt).
#include "fuzz_mutator.hpp"
#include "fuzz_target.hpp"

#include <cstring>

extern "C" std::size_t LLVMFuzzerMutate(std::uint8_t* data, std::size_t size, std::size_t max_size);

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return hapsyn::fuzz::fuzz_one(data, size);
}

extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned int seed) {
  std::mt19937_64 rng(seed);
  if (rng() % 2 == 0) return LLVMFuzzerMutate(data, size, max_size);
  std::string input(reinterpret_cast<const char*>(data), size);
  hapsyn::fuzz::mutate_structure(input, max_size, rng);
  std::memcpy(data, input.data(), input.size());
  return input.size();
}
