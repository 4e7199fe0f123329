#!/usr/bin/env bash
# The long attack campaign (tests/attack/README.md): builds hapsyn if needed, then runs
# tests/attack/attack.py with many inputs per class and writes the table.
#
#   bash scripts/attack.sh                     # 200 inputs per class, seed 1, 2 jobs
#   HAPSYN_ATTACK_N=1000 HAPSYN_ATTACK_SEED=7 bash scripts/attack.sh --classes json,set
#
# Extra arguments go to attack.py. Output: the table on stdout and in
# $build/attack/attack-long.txt, every case in $build/attack/attack-long.json. Exit status 1
# if any case failed (crash, hang, internal, wrong, mixed). Run as root for the full-filesystem
# cases (they mount a 200 KiB tmpfs); otherwise they are skipped with the reason.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${HAPSYN_BUILD_DIR:-$root/build}"
n="${HAPSYN_ATTACK_N:-200}"
seed="${HAPSYN_ATTACK_SEED:-1}"
jobs="${HAPSYN_ATTACK_JOBS:-2}"
if [[ ! -x "$build/bin/hapsyn" || -n "${HAPSYN_ATTACK_REBUILD:-}" ]]; then
  bash "$root/scripts/setup.sh"
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DHAPSYN_BUILD_TESTS=ON >/dev/null
  plugins=$(cd "$build" && ninja -t targets all | sed -n 's/^\(hapsyn_plugin_[a-z0-9_]*\): phony$/\1/p' |
            grep -v -E 'badversion|throwing|nanmetric' | tr '\n' ' ')
  # shellcheck disable=SC2086
  cmake --build "$build" --target hapsyn_cli $plugins
fi
mkdir -p "$build/attack"
work="$build/attack/work-long"
rm -rf "$work"
set +e
python3 "$root/tests/attack/attack.py" --hapsyn "$build/bin/hapsyn" --seed "$seed" --per-class "$n" --jobs "$jobs" \
  --n signal="${HAPSYN_ATTACK_SIGNAL_N:-20}" --work "$work" --json "$build/attack/attack-long.json" "$@" |
  tee "$build/attack/attack-long.txt"
status=${PIPESTATUS[0]}
set -e
echo "table: $build/attack/attack-long.txt, cases: $build/attack/attack-long.json, sandboxes of failing cases: $work/cases"
exit "$status"
