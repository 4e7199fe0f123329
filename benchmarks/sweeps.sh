#!/usr/bin/env bash
# The speed-versus-accuracy sweeps of the README, reproducible with one command each.
# Usage: benchmarks/sweeps.sh [BUILD_DIR]   (default build/; results under results/sweeps/)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
hapsyn="${1:-$root/build}/bin/hapsyn"
out="$root/results/sweeps"
cd "$root"

# Five-bar: workspace step (GII, culling + polish, 10 mm design grid).
"$hapsyn" sweep problems/fivebar-gii-culling-coarse.json --force --out "$out/fivebar-workspace-step" \
  --vary scene.options.step=0.01,0.005,0.002,0.001

# Five-bar: culling design grid step without polishing (GDI, 5 mm workspace).
"$hapsyn" sweep problems/fivebar-gdi-culling-coarse.json --force --out "$out/fivebar-design-step" \
  --set solver.options.polish=false \
  --vary design.l0.step,design.l1.step,design.l2.step,design.r.step=0.02,0.01,0.005

# Five-bar: culling design grid step with polishing, against the paper-resolution study.
"$hapsyn" sweep problems/fivebar-gii-culling-paper.json --force --out "$out/fivebar-design-step-polished" \
  --vary design.l0.step,design.l1.step,design.l2.step,design.r.step=0.02,0.01,0.005,0.002

# Human arm scene knobs, measured on the coverage objectives of the haptic 6R evaluate study
# (cache off: the run time includes building the scene).
"$hapsyn" sweep problems/haptic6r-evaluate.json --force --set scene.options.cache=false --out "$out/human-lattice-step" \
  --vary scene.options.lattice_step=0.2,0.1,0.05
"$hapsyn" sweep problems/haptic6r-evaluate.json --force --set scene.options.cache=false --out "$out/human-orientations" \
  --vary scene.options.orientations=101,252,505,1010,2020
"$hapsyn" sweep problems/haptic6r-evaluate.json --force --set scene.options.cache=false --out "$out/human-joint3-steps" \
  --vary scene.options.joint3_steps=5,9,17,33,65

# Five-bar Pareto front (GII vs GDI): NBI constraint tolerance (Unal Figures 4-5) and grid size;
# each run's front is measured against the last run's (IGD) and the exhaustive reference front
# named in the problem (result.json "indicators"; run problems/fivebar-pareto-reference.json first).
"$hapsyn" run problems/fivebar-pareto-reference.json --quiet
"$hapsyn" sweep problems/fivebar-pareto-nbi.json --force --out "$out/nbi-tolerance" \
  --vary solver.options.constraint_tolerance=1e-7,1e-8,1e-9
"$hapsyn" sweep problems/fivebar-pareto-nbi.json --force --out "$out/nbi-points" \
  --vary solver.options.points=5,10,20,40
# The weighted sum's design grid step (its accuracy knob), for the time comparison.
"$hapsyn" sweep problems/fivebar-pareto-weighted-sum.json --force --out "$out/weighted-sum-step" \
  --vary design.l0.step,design.l1.step,design.l2.step,design.r.step=0.02,0.01,0.005
