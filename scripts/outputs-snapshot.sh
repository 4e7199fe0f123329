#!/usr/bin/env bash
# Runs shipped problems with one hapsyn binary and keeps their per-sample outputs, so that two
# builds can be compared file by file (the outputs phase must not change them):
#
#   scripts/outputs-snapshot.sh run HAPSYN OUT_DIR problems/a.json problems/b.json ...
#   scripts/outputs-snapshot.sh compare OUT_DIR_A OUT_DIR_B
#
# `run` writes OUT_DIR/<problem>/ (2 threads, quiet) and OUT_DIR/<problem>.phases (result.json's
# phase timings). `compare` cmp's every .csv and .dat (samples.csv, maps.csv, groups.csv, the
# map and timeline plot data) of every problem present in both directories and exits non-zero
# when one differs. result.json and run.log are not compared: they hold wall times.
set -euo pipefail

compared_files() {  # the per-sample outputs of one run directory
  (cd "$1" && ls -- *.csv *.dat 2>/dev/null || true)
}

case "${1:-}" in
  run)
    hapsyn=$2 out=$3
    shift 3
    mkdir -p "$out"
    for problem in "$@"; do
      name=$(basename "$problem" .json)
      "$hapsyn" run "$problem" --out "$out/$name" --threads 2 --quiet --force
      python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(json.dumps(d["phases"]))' \
        "$out/$name/result.json" > "$out/$name.phases"
      echo "$name: $(cat "$out/$name.phases")"
    done
    ;;
  compare)
    a=$2 b=$3 status=0
    for dir in "$a"/*/; do
      name=$(basename "$dir")
      [ -d "$b/$name" ] || continue
      files=$(compared_files "$a/$name")
      if [ "$files" != "$(compared_files "$b/$name")" ]; then
        echo "$name: different file sets: $(echo $files) / $(echo $(compared_files "$b/$name"))"
        status=1
        continue
      fi
      for f in $files; do
        if ! cmp -s "$a/$name/$f" "$b/$name/$f"; then
          echo "$name: $f differs"
          status=1
        fi
      done
      echo "$name: compared $(echo $files)"
    done
    exit $status
    ;;
  *)
    sed -n '2,11p' "$0"
    exit 2
    ;;
esac
