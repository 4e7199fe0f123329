#!/usr/bin/env bash
# Builds hapsyn with AddressSanitizer + UndefinedBehaviorSanitizer and runs the fast tests.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_ASAN_BUILD_DIR:-$root/build-asan}"
bash "$root/scripts/setup.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHAPSYN_SANITIZE=ON >/dev/null
cmake --build "$build"
# Leak checking stays on; the out-of-tree test builds a separate (uninstrumented) plugin, so it
# runs in the ordinary build only.
ctest --test-dir "$build" --output-on-failure -j2 -L fast -LE slow -E OutOfTree
