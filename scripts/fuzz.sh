#!/usr/bin/env bash
# Builds the libFuzzer target with clang (ASan + UBSan) and runs the labelled fuzz test.
# HAPSYN_FUZZ_SECONDS sets its duration (default 60). A crash leaves its input in
# build-fuzz/fuzz-artifacts/; add it to tests/fuzz/regressions/ so the default suite replays it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_FUZZ_BUILD_DIR:-$root/build-fuzz}"
HAPSYN_EXTRA_PACKAGES="clang libclang-rt-dev ${HAPSYN_EXTRA_PACKAGES:-}" bash "$root/scripts/setup.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DHAPSYN_BUILD_FUZZERS=ON -DHAPSYN_FUZZ_SECONDS="${HAPSYN_FUZZ_SECONDS:-60}" >/dev/null
cmake --build "$build"
ctest --test-dir "$build" --output-on-failure -L fuzz
