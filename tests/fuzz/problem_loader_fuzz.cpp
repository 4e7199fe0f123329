// libFuzzer target (HAPSYN_BUILD_FUZZERS=ON, clang): the problem loader and the --set parser.
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return hapsyn::fuzz::fuzz_one(data, size);
}
