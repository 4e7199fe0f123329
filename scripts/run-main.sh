#!/usr/bin/env bash
# The main job: installs what is missing (apt), builds hapsyn (Release), and runs the ready study
# problems/fivebar-gii-coarse.json (exhaustive GII search of the Unal five-bar on a 10 mm grid),
# printing its result. It builds every plugin, so that any other study of problems/ runs after
# it. Extra arguments go to `hapsyn run` (e.g. --threads 1, --set ...).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_BUILD_DIR:-$root/build}"
bash "$root/scripts/setup.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
# The program and every shipped plugin (not the tests): any study of problems/ then runs, and
# `build/bin/hapsyn view PROBLEM` shows it.
cmake --build "$build" --target hapsyn_cli hapsyn_plugins
cd "$root"
exec "$build/bin/hapsyn" run problems/fivebar-gii-coarse.json --force "$@"
