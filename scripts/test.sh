#!/usr/bin/env bash
# Builds hapsyn with its tests and runs the default test suite (everything not labelled
# "slow"). Installs missing packages first. Extra arguments go to ctest
# (e.g. -L slow for the long checks, -R Grid to select).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_BUILD_DIR:-$root/build}"
bash "$root/scripts/setup.sh"
# The browser for hapsyn view's page tests installs while the build runs (the build needs none of it).
mkdir -p "$build"
bash "$root/scripts/setup.sh" --browser >"$build/setup-browser.log" 2>&1 &
browser_setup=$!
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DHAPSYN_BUILD_TESTS=ON >/dev/null
cmake --build "$build"
if ! wait "$browser_setup"; then
  echo "hapsyn test: installing the browser failed (see $build/setup-browser.log); its tests will fail" >&2
fi
if [[ $# -eq 0 ]]; then set -- -LE slow; fi
ctest --test-dir "$build" --output-on-failure -j2 "$@"
