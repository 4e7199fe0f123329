#!/usr/bin/env bash
# The main job: installs what is missing (apt), builds hapsyn (Release), and runs the ready study
# problems/fivebar-gii-coarse.json (exhaustive GII search of the Unal five-bar on a 10 mm grid),
# printing its result. Extra arguments go to `hapsyn run` (e.g. --threads 1, --set ...).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_BUILD_DIR:-$root/build}"
bash "$root/scripts/setup.sh"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build" --target hapsyn_cli hapsyn_plugin_fivebar hapsyn_plugin_planar_square \
  hapsyn_plugin_gii hapsyn_plugin_gdi hapsyn_plugin_grid hapsyn_plugin_evaluate
cd "$root"
exec "$build/bin/hapsyn" run problems/fivebar-gii-coarse.json --force "$@"
