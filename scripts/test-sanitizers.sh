#!/usr/bin/env bash
# Builds hapsyn with clang, AddressSanitizer and UndefinedBehaviorSanitizer (and the libFuzzer
# target), runs the fast tests there, then the labelled fuzz test for HAPSYN_FUZZ_SECONDS
# (default 60). Installs missing packages first. This build is the one without MPI
# (HAPSYN_WITH_MPI=OFF): it proves the option gates the dependency, and tests the message of such
# a build started by mpirun; the MPI cluster itself is tested end to end in scripts/test.sh.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_SANITIZE_BUILD_DIR:-$root/build-sanitize}"
HAPSYN_EXTRA_PACKAGES="clang libclang-rt-dev ${HAPSYN_EXTRA_PACKAGES:-}" bash "$root/scripts/setup.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DHAPSYN_BUILD_FUZZERS=ON -DHAPSYN_FUZZ_SECONDS="${HAPSYN_FUZZ_SECONDS:-60}" -DHAPSYN_WITH_MPI=OFF >/dev/null
cmake --build "$build"
# The out-of-tree test builds an uninstrumented plugin against the installed package: it runs in
# the ordinary build (scripts/test.sh) only.
ctest --test-dir "$build" --output-on-failure -j2 -L fast -LE slow -E OutOfTree
ctest --test-dir "$build" --output-on-failure -L fuzz
