#!/usr/bin/env bash
# The speed-versus-accuracy sweeps of the README, reproducible with one command each.
# Usage: benchmarks/sweeps.sh [BUILD_DIR]   (default build/; results under results/sweeps/)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hapsyn="${1:-$root/build}/bin/hapsyn"
out="$root/results/sweeps"
cd "$root"

# Five-bar: workspace step (GII, culling + polish, 10 mm design grid).
"$hapsyn" sweep problems/fivebar-gii-culling-coarse.json --out "$out/fivebar-workspace-step" \
  --vary scene.options.step=0.01,0.005,0.002,0.001

# Five-bar: culling design grid step without polishing (GDI, 5 mm workspace).
"$hapsyn" sweep problems/fivebar-gdi-culling-coarse.json --out "$out/fivebar-design-step" \
  --set solver.options.polish=false \
  --vary design.l0.step,design.l1.step,design.l2.step,design.r.step=0.02,0.01,0.005

# Five-bar: culling design grid step with polishing, against the paper-resolution study.
"$hapsyn" sweep problems/fivebar-gii-culling-paper.json --out "$out/fivebar-design-step-polished" \
  --vary design.l0.step,design.l1.step,design.l2.step,design.r.step=0.02,0.01,0.005,0.002
