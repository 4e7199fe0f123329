#!/usr/bin/env bash
# A/B of two builds on a noisy machine: runs one Google Benchmark binary of each build in turn,
# ROUNDS times, and prints the best real time of each benchmark per build (the alternation puts
# both builds under the same load; the best of several rounds is the least disturbed).
#
#   bash benchmarks/ab.sh OLD_BUILD_DIR NEW_BUILD_DIR BINARY FILTER [ROUNDS]
#   bash benchmarks/ab.sh /work/base/build build haptic6r_benchmark 'FullObjectivePerDesign' 5
set -euo pipefail
if [[ $# -lt 4 ]]; then
  echo "usage: $0 OLD_BUILD_DIR NEW_BUILD_DIR BINARY FILTER [ROUNDS]" >&2
  exit 2
fi
old="$1"; new="$2"; binary="$3"; filter="$4"; rounds="${5:-5}"
for dir in "$old" "$new"; do
  if [[ ! -x "$dir/bin/$binary" ]]; then
    echo "ab.sh: $dir/bin/$binary: not an executable (build it with -DHAPSYN_BUILD_BENCHMARKS=ON)" >&2
    exit 2
  fi
done
uname -srm; grep -m1 "model name" /proc/cpuinfo || true; uptime
for ((i = 1; i <= rounds; ++i)); do
  for side in old new; do
    dir="$old"; [[ $side == new ]] && dir="$new"
    # The console report (some benchmark mains install their own reporter), colours stripped.
    "$dir/bin/$binary" --benchmark_filter="$filter" --benchmark_min_time=0.5 --benchmark_color=false 2>/dev/null |
      sed 's/\x1b\[[0-9;]*m//g' | awk -v side="$side" '$1 ~ /^BM_/ { print side, $1, $2, $3 }'
  done
done | awk '{ key = $1 " " $2; if (!(key in best) || $3 < best[key]) { best[key] = $3; unit[key] = $4 } }
            END { for (k in best) print k, best[k], unit[k] }' | sort -k2,2 -k1,1r
