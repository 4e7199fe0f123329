#!/usr/bin/env python3
"""Python peers of hapsyn's five-bar studies: the baselines of the five-bar speed issue (issue 16).

Written the way a careful researcher would write them without hapsyn, on the same model
(plugins/mechanisms/fivebar, gii, gdi, planar_square): elbow-out inverse kinematics, the
unreachable / singular / invalid / reachable classification with hapsyn's tolerances (8 eps
rounding bound of the law of cosines, singularity_tolerance 1e-4 on |sin(q1 - q2)|,
|sin(q3 - q4)|, |sin(q3 - q2)|, 1e-9 rad on the angle limits of the paper's G), the derived
Jacobian J, the inertia D and the effective mass M = J^-T D J^-1, GII = min sigma_min(J) /
max sigma_max(J) and GDI = 1 / (1 + max sigma_max(M)).

Subcommands (each prints one JSON line: seconds, best value, best design, designs, samples):

  numba-grid --threads N [--prune] [--check RESULT_JSON]
      Exhaustive GII search of the design grid of problems/fivebar-gii-coarse.json (1,701,900
      designs, 441 samples), a numba @njit(parallel=True, fastmath=False, cache=False) kernel
      with prange over the (l0, l1) rows of the grid. Inverse kinematics without trigonometric
      functions (law of cosines and unit vectors); validity and singularity from the cross
      products of the link vectors (see `classify` below for why this is hapsyn's G exactly).
      The reach constraint first, the workspace samples extremes first (hapsyn's sample order),
      a design's sample loop stops at its first failing sample. --prune: incumbent pruning (a
      design stops once min sigma_min / max sigma_max over its samples so far is strictly below
      the best found); the threads share their incumbents through an array of per-row bests that
      each row reads when it starts and at every l2 step. JIT compilation is excluded (warm-up
      on a tiny grid); the best of --repeats (3) timed runs is reported.
  numpy-grid [--check RESULT_JSON]
      The same search in plain NumPy on one core: vectorised over the designs (every design
      that passes the reach constraint, in blocks), a loop over the samples in the same order,
      designs dropped at their first failing sample. Uses hapsyn's angle formulas (atan2, acos)
      and its literal G, so it also checks the trig-free classification of numba-grid.
  deap-nsga2 --population 200 --generations 3000 --seed S [--threads N]
      DEAP's NSGA-II (tools.selNSGA2, selTournamentDCD, cxSimulatedBinaryBounded,
      mutPolynomialBounded) with pagmo's NSGA-II parameters as hapsyn's nsga2 uses them
      (cr 0.95, eta_c 10, m 0.01 per component, eta_m 50) on the continuous box of
      problems/fivebar-pareto-nsga2.json, maximising worst-case GII and GDI; one numba batch
      evaluation per generation. Infeasible designs get hapsyn's pagmo-adapter penalties
      (-1e9 in every objective when a sample fails, -(2e9 + violation) when the reach
      constraint fails: dominated by every feasible design). Reports the hypervolume of the
      final front with reference point (0, 0) in natural units, no normalisation (how
      hapsyn's result.json states it for the five-bar Pareto studies).
  self-test [--hapsyn PATH]
      On a 3x3x3x5 sub-grid, numba's per-design GII and GDI (and feasibility) against hapsyn's
      (one `hapsyn sweep` of the evaluate solver over the 135 designs) to 1e-12 relative, and
      the trig-free classification against the angle-based one on random designs and samples.

Run from the repository root (needs numba and deap for /usr/bin/python3:
`HAPSYN_EXTRA_PACKAGES="python3-numba python3-deap" bash scripts/setup.sh`), e.g.
    /usr/bin/python3 benchmarks/fivebar_peers.py numba-grid --threads 2 --prune \\
        --check results/fivebar-gii-coarse/result.json
"""
import argparse
import json
import math
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
GRID_PROBLEM = os.path.join(ROOT, "problems", "fivebar-gii-coarse.json")
NSGA2_PROBLEM = os.path.join(ROOT, "problems", "fivebar-pareto-nsga2.json")

EPS = float(np.finfo(np.float64).eps)
PI = 3.14159265358979323846
ANGLE_TOL = 1e-9  # kFiveBarAngleTolerance [rad]
# Status of a design evaluation (hapsyn's EvalStatus).
FEASIBLE, CONSTRAINT_VIOLATED, SAMPLE_FAILED, PRUNED = 0, 1, 2, 3
# Class of a sample (hapsyn's SampleStatus).
REACHABLE, UNREACHABLE, SINGULAR, INVALID = 0, 1, 2, 3
# pagmo adapter penalties (plugins/solvers/shared/pagmo_adapter.hpp), as maximised objectives.
SAMPLE_FAILED_FITNESS = -1e9
CONSTRAINT_FITNESS = -2e9


# ----------------------------------------------------------------------------------------------
# The study: scene, sample order, design grid, mechanism options (read from the problem file)
# ----------------------------------------------------------------------------------------------

class Study:
    """What the peers need of a five-bar problem file: samples in hapsyn's order, bounds, grid."""

    def __init__(self, path):
        with open(path) as f:
            problem = json.load(f)
        self.path = path
        self.problem = problem
        mech = problem["mechanism"]
        assert mech["plugin"] == "fivebar" and problem["scene"]["plugin"] == "planar_square"
        options = mech.get("options", {})
        self.rho = float(options.get("rho", 1.08))
        self.k = float(options.get("k", 0.005))
        self.singularity_tolerance = float(options.get("singularity_tolerance", 1e-4))
        scene = problem["scene"].get("options", {})
        side, step = float(scene.get("side", 0.1)), float(scene.get("step", 0.005))
        n = int(round(side / step)) + 1
        # planar_square: x_j = (2 j - (n - 1)) / (2 (n - 1)) * side, row-major, x fastest.
        coordinate = np.array([(2.0 * j - (n - 1)) / (2.0 * (n - 1)) * side for j in range(n)])
        xs = np.tile(coordinate, n)
        ys = np.repeat(coordinate, n)
        # Problem::sample_order: worst-case metrics visit the samples far from the centroid first
        # (stable sort by squared distance, descending).
        centroid = np.array([xs.mean(), ys.mean()])
        distance = (xs - centroid[0]) ** 2 + (ys - centroid[1]) ** 2
        order = np.argsort(-distance, kind="stable")
        self.xs = np.ascontiguousarray(xs[order])
        self.ys = np.ascontiguousarray(ys[order])
        self.sample_index = order  # scene index of the i-th visited sample
        self.box = np.array([xs.min(), xs.max(), ys.min(), ys.max()])
        self.names = ["l0", "l1", "l2", "r"]
        design = problem["design"]
        self.lower = np.array([float(design[v]["lower"]) for v in self.names])
        self.upper = np.array([float(design[v]["upper"]) for v in self.names])
        self.steps = [design[v].get("step") for v in self.names]

    def axes(self):
        """Grid values per variable: lower + i * step (not repeated addition), capped at upper."""
        axes = []
        for lo, up, st in zip(self.lower, self.upper, self.steps):
            n = (up - lo) / st
            count = int(math.floor(n + 1e-9 * max(1.0, n))) + 1  # DesignSpace::grid_count
            axes.append(np.minimum(up, lo + np.arange(count, dtype=np.float64) * st))
        return axes

    def mass_constants(self):
        return np.array([self.rho, self.k, self.singularity_tolerance])


# ----------------------------------------------------------------------------------------------
# The numba model (no trigonometric functions)
# ----------------------------------------------------------------------------------------------

def _numba():
    import numba
    return numba


def build_kernels():
    """Compiles nothing yet: defines the numba functions (numba is imported lazily so that
    numpy-grid runs without it)."""
    numba = _numba()
    from numba import njit, prange

    @njit(cache=False, fastmath=False, error_model="numpy", inline="always")
    def solve_leg(dx, dy, l1, l2):
        """Elbow-out IK of one leg, E - A = (dx, dy): (code, ux, uy, wx, wy); code 0 solved,
        1 unreachable, 2 end effector on the actuated joint (folded leg, singular)."""
        rho2 = dx * dx + dy * dy
        rho = np.sqrt(rho2)
        diff = (l1 - l2) * (l1 + l2)  # l1^2 - l2^2 without cancellation
        spread = l1 * l1 + l2 * l2 + rho2
        if not (rho > 0.0):
            if abs(diff) <= 8.0 * EPS * spread:
                return 2, 0.0, 0.0, 0.0, 0.0
            return 1, 0.0, 0.0, 0.0, 0.0
        den = 2.0 * l1 * rho
        c = (diff + rho2) / den  # law of cosines: cos of the angle between E - A and the link
        tolerance = 8.0 * EPS * spread / den  # rounding bound of c on the reach boundary
        if not (abs(c) <= 1.0 + tolerance):
            return 1, 0.0, 0.0, 0.0, 0.0
        if c < -1.0:
            c = -1.0
        elif c > 1.0:
            c = 1.0
        s = np.sqrt((1.0 - c) * (1.0 + c))  # sin of that angle, >= 0: elbow out
        ex = dx / rho
        ey = dy / rho
        ux = c * ex - s * ey  # unit vector of the actuated link: E - A turned by +acos(c)
        uy = c * ey + s * ex
        wx = dx - l1 * ux  # free link E - B
        wy = dy - l1 * uy
        return 0, ux, uy, wx, wy

    @njit(cache=False, fastmath=False, error_model="numpy", inline="always")
    def classify(x, y, l0, l1, l2, tol):
        """Class of the sample E = (x, y) [mechanism frame] and the link vectors
        (u1, w1, u4, w2, in the mechanism frame).

        Validity without angles. hapsyn's G is q2 >= 0, q2 <= q1, q3 <= pi, q4 <= q3 (1e-9 rad)
        and 0 < q3 - q2 < pi with q2 in [-pi/2, 3pi/2), q3 in (-pi/2, 3pi/2]. Once the three
        transmission sines are >= 1e-4 in magnitude (checked first, as hapsyn does), it is:
          - q2, q3 in [-t, pi + t]       <=>  w1_y >= -l2 t and w2_y >= -l2 t (w_i = l2 (cos, sin));
          - 0 < q3 - q2 < pi             <=>  cross(w1, w2) = l2^2 sin(q3 - q2) > 0;
          - q2 <= q1 (q4 <= q3 mirrored) <=>  E_y >= 0: with E below the actuators' line an
            elbow-out leg whose free link points up has q2 (its [-pi/2, 3pi/2) representative)
            above q1 = atan2(E - A) + acos(c) in (-pi, 0]; on or above the line it is below.
        The equivalence holds up to rounding at the 1e-9 rad limits (a sample would have to sit
        within ~1e-16 rad of a limit); --self-test checks it against the angle formulas."""
        h0 = 0.5 * l0
        cl, u1x, u1y, w1x, w1y = solve_leg(x + h0, y, l1, l2)
        cr, rux, ruy, rwx, rwy = solve_leg(h0 - x, y, l1, l2)  # right leg, mirrored frame
        if cl == 1 or cr == 1:
            return UNREACHABLE, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        if cl == 2 or cr == 2:
            return SINGULAR, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        u4x = -rux
        u4y = ruy
        w2x = -rwx
        w2y = rwy
        s12 = (w1x * u1y - w1y * u1x) / l2  # sin(q1 - q2)
        s34 = (rwx * ruy - rwy * rux) / l2  # sin(q3 - q4)
        cross12 = w1x * w2y - w1y * w2x  # l2^2 sin(q3 - q2)
        s23 = cross12 / (l2 * l2)
        if not (abs(s12) >= tol and abs(s34) >= tol and abs(s23) >= tol):
            return SINGULAR, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y
        limit = -l2 * ANGLE_TOL
        if not (w1y >= limit and w2y >= limit and cross12 > 0.0 and y >= 0.0):
            return INVALID, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y
        return REACHABLE, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y

    @njit(cache=False, fastmath=False, error_model="numpy", inline="always")
    def jacobian(l1, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y):
        """J = W^-1 diag(b1, b2), W = [w1^T; w2^T], b_i = l1 cross(u_i, w_i); and b1, b2."""
        b1 = l1 * (u1x * w1y - u1y * w1x)
        b2 = l1 * (u4x * w2y - u4y * w2x)
        inv_det = 1.0 / (w1x * w2y - w1y * w2x)
        a = w2y * b1 * inv_det
        b = -w1y * b2 * inv_det
        c = -w2x * b1 * inv_det
        d = w1x * b2 * inv_det
        return a, b, c, d, b1, b2

    @njit(cache=False, fastmath=False, error_model="numpy", inline="always")
    def singular_values(a, b, c, d):
        """sigma_min, sigma_max of [[a, b], [c, d]] (gii's closed form)."""
        e = 0.5 * (a + d)
        f = 0.5 * (a - d)
        g = 0.5 * (c + b)
        h = 0.5 * (c - b)
        smax = np.sqrt(e * e + h * h) + np.sqrt(f * f + g * g)
        smin = abs(a * d - b * c) / smax if smax > 0.0 else 0.0
        if smin > smax:
            smin = smax
        return smin, smax

    @njit(cache=False, fastmath=False, error_model="numpy", inline="always")
    def mass_sigma_max(l1, l2, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y, ja, jb, jc, jd, b1, b2,
                       m2, inertia_a, inertia_f):
        """Largest singular value of M = J^-T D J^-1 (fivebar.cpp's D, gdi's closed form)."""
        l2s = l2 * l2
        # P1 = [l1 perp(u1), 0], P2 = [0, l1 perp(u4)]; C_i = (P_i + J) / 2
        p1x = -l1 * u1y
        p1y = l1 * u1x
        p2x = -l1 * u4y
        p2y = l1 * u4x
        c1_00 = 0.5 * (p1x + ja)
        c1_01 = 0.5 * (0.0 + jb)
        c1_10 = 0.5 * (p1y + jc)
        c1_11 = 0.5 * (0.0 + jd)
        c2_00 = 0.5 * (0.0 + ja)
        c2_01 = 0.5 * (p2x + jb)
        c2_10 = 0.5 * (0.0 + jc)
        c2_11 = 0.5 * (p2y + jd)
        # a_i = (J - P_i)^T perp(w_i) / l2^2
        a2_0 = ((ja - p1x) * -w1y + (jc - p1y) * w1x) / l2s
        a2_1 = ((jb - 0.0) * -w1y + (jd - 0.0) * w1x) / l2s
        a3_0 = ((ja - 0.0) * -w2y + (jc - 0.0) * w2x) / l2s
        a3_1 = ((jb - p2x) * -w2y + (jd - p2y) * w2x) / l2s
        # D = m2 (C1^T C1 + C2^T C2) + I_f (a2 a2^T + a3 a3^T) + I_a 1
        d00 = m2 * ((c1_00 * c1_00 + c1_10 * c1_10) + (c2_00 * c2_00 + c2_10 * c2_10)) + inertia_f * (
            a2_0 * a2_0 + a3_0 * a3_0) + inertia_a
        d01 = m2 * ((c1_00 * c1_01 + c1_10 * c1_11) + (c2_00 * c2_01 + c2_10 * c2_11)) + inertia_f * (
            a2_0 * a2_1 + a3_0 * a3_1)
        d10 = m2 * ((c1_01 * c1_00 + c1_11 * c1_10) + (c2_01 * c2_00 + c2_11 * c2_10)) + inertia_f * (
            a2_1 * a2_0 + a3_1 * a3_0)
        d11 = m2 * ((c1_01 * c1_01 + c1_11 * c1_11) + (c2_01 * c2_01 + c2_11 * c2_11)) + inertia_f * (
            a2_1 * a2_1 + a3_1 * a3_1) + inertia_a
        # J^-1 = diag(b1, b2)^-1 W; M = J^-T D J^-1
        k00 = w1x / b1
        k01 = w1y / b1
        k10 = w2x / b2
        k11 = w2y / b2
        t00 = k00 * d00 + k10 * d10  # (J^-T D)
        t01 = k00 * d01 + k10 * d11
        t10 = k01 * d00 + k11 * d10
        t11 = k01 * d01 + k11 * d11
        ma = t00 * k00 + t01 * k10
        mb = t00 * k01 + t01 * k11
        mc = t10 * k00 + t11 * k10
        md = t10 * k01 + t11 * k11
        e = 0.5 * (ma + md)
        f = 0.5 * (ma - md)
        g = 0.5 * (mc + mb)
        h = 0.5 * (mc - mb)
        return np.sqrt(e * e + h * h) + np.sqrt(f * f + g * g)

    @njit(cache=False, fastmath=False, error_model="numpy", inline="always")
    def reach(l0, l1, l2, r, box):
        """FiveBar::reach_constraint over the scene's bounding box [m^2] (<= 0 holds)."""
        xmin, xmax, ymin, ymax = box[0], box[1], box[2], box[3]
        h0 = 0.5 * l0
        ay = max(abs(ymin + r), abs(ymax + r))
        ax1 = max(abs(xmin + h0), abs(xmax + h0))
        ax2 = max(abs(xmin - h0), abs(xmax - h0))
        ax = max(ax1, ax2)
        s = l1 + l2
        return (ax * ax + ay * ay) - s * s

    @njit(cache=False, fastmath=False, error_model="numpy")
    def design_gii(l0, l1, l2, r, xs, ys, box, tol, prune_below):
        """(status, GII, samples solved) of one design; samples in hapsyn's order."""
        if reach(l0, l1, l2, r, box) > 0.0:
            return CONSTRAINT_VIOLATED, 0.0, 0
        min_smin = np.inf
        max_smax = -np.inf
        n = xs.shape[0]
        for i in range(n):
            cls, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y = classify(xs[i], ys[i] + r, l0, l1, l2, tol)
            if cls != REACHABLE:
                return SAMPLE_FAILED, 0.0, i + 1
            ja, jb, jc, jd, b1, b2 = jacobian(l1, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y)
            smin, smax = singular_values(ja, jb, jc, jd)
            if smin < min_smin:
                min_smin = smin
            if smax > max_smax:
                max_smax = smax
            if prune_below > -np.inf:  # worst-case bound from the samples so far (gii's combine)
                bound = min_smin / max_smax if max_smax > 0.0 and max_smax < np.inf else 0.0
                if bound < prune_below:
                    return PRUNED, bound, i + 1
        value = min_smin / max_smax if max_smax > 0.0 and max_smax < np.inf else 0.0
        return FEASIBLE, value, n

    @njit(parallel=True, fastmath=False, cache=False, error_model="numpy")
    def grid_search(a0, a1, a2, a3, xs, ys, box, tol, prune, row_order):
        """Exhaustive search of the grid a0 x a1 x a2 x a3 (grid index: last variable fastest).
        prange over the (l0, l1) rows, visited in row_order (interleaved so that the static
        split of prange gives each thread rows from the whole grid). Per row: best value and
        index (ties to the lower index), counts (feasible, constraint violated, sample failed,
        pruned, samples solved). With prune, `incumbent[row]` holds the row's best so far; a row
        reads the largest entry when it starts and at every l2 step (stale reads only prune
        less; every entry is a real design's value, so nothing that ties or beats the optimum
        is cut)."""
        n0, n1, n2, n3 = a0.shape[0], a1.shape[0], a2.shape[0], a3.shape[0]
        rows = n0 * n1
        best_val = np.full(rows, -np.inf)
        best_idx = np.full(rows, -1, dtype=np.int64)
        counts = np.zeros((rows, 5), dtype=np.int64)
        incumbent = np.full(rows, -np.inf)
        for k in prange(rows):
            row = row_order[k]
            i0 = row // n1
            i1 = row - i0 * n1
            l0 = a0[i0]
            l1 = a1[i1]
            local = -np.inf
            bv = -np.inf
            bi = -1
            c_feasible = 0
            c_constraint = 0
            c_failed = 0
            c_pruned = 0
            c_samples = 0
            for i2 in range(n2):
                l2 = a2[i2]
                if prune:
                    shared = incumbent.max()
                    if shared > local:
                        local = shared
                base = (row * n2 + i2) * n3
                for i3 in range(n3):
                    status, value, solved = design_gii(l0, l1, l2, a3[i3], xs, ys, box, tol,
                                                       local if prune else -np.inf)
                    c_samples += solved
                    if status == FEASIBLE:
                        c_feasible += 1
                        if value > bv:
                            bv = value
                            bi = base + i3
                        if prune and value > local:
                            local = value
                            incumbent[row] = value
                    elif status == CONSTRAINT_VIOLATED:
                        c_constraint += 1
                    elif status == SAMPLE_FAILED:
                        c_failed += 1
                    else:
                        c_pruned += 1
            best_val[row] = bv
            best_idx[row] = bi
            counts[row, 0] = c_feasible
            counts[row, 1] = c_constraint
            counts[row, 2] = c_failed
            counts[row, 3] = c_pruned
            counts[row, 4] = c_samples
        return best_val, best_idx, counts

    @njit(cache=False, fastmath=False, error_model="numpy")
    def design_gii_gdi(l0, l1, l2, r, xs, ys, box, consts):
        """(status, GII, GDI, samples solved, violation) of one design, no pruning."""
        g = reach(l0, l1, l2, r, box)
        if g > 0.0:
            return CONSTRAINT_VIOLATED, 0.0, 0.0, 0, g
        rho, kk, tol = consts[0], consts[1], consts[2]
        m1 = rho * l1
        m2 = rho * l2
        k2 = kk * kk
        inertia_a = m1 * (4.0 * l1 * l1 + k2) / 12.0
        inertia_f = m2 * (l2 * l2 + k2) / 12.0
        min_smin = np.inf
        max_smax = -np.inf
        max_mass = -np.inf
        n = xs.shape[0]
        for i in range(n):
            cls, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y = classify(xs[i], ys[i] + r, l0, l1, l2, tol)
            if cls != REACHABLE:
                return SAMPLE_FAILED, 0.0, 0.0, i + 1, 0.0
            ja, jb, jc, jd, b1, b2 = jacobian(l1, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y)
            smin, smax = singular_values(ja, jb, jc, jd)
            mass = mass_sigma_max(l1, l2, u1x, u1y, w1x, w1y, u4x, u4y, w2x, w2y, ja, jb, jc, jd, b1, b2,
                                  m2, inertia_a, inertia_f)
            if smin < min_smin:
                min_smin = smin
            if smax > max_smax:
                max_smax = smax
            if mass > max_mass:
                max_mass = mass
        gii = min_smin / max_smax if max_smax > 0.0 and max_smax < np.inf else 0.0
        gdi = 1.0 / (1.0 + max_mass)
        return FEASIBLE, gii, gdi, n, 0.0

    @njit(parallel=True, fastmath=False, cache=False, error_model="numpy")
    def batch_gii_gdi(designs, xs, ys, box, consts):
        """Per design (rows of designs: l0, l1, l2, r): status, GII, GDI, samples, violation."""
        n = designs.shape[0]
        status = np.zeros(n, dtype=np.int64)
        values = np.zeros((n, 2))
        samples = np.zeros(n, dtype=np.int64)
        violation = np.zeros(n)
        for i in prange(n):
            s, gii, gdi, solved, g = design_gii_gdi(designs[i, 0], designs[i, 1], designs[i, 2], designs[i, 3],
                                                    xs, ys, box, consts)
            status[i] = s
            values[i, 0] = gii
            values[i, 1] = gdi
            samples[i] = solved
            violation[i] = g
        return status, values, samples, violation

    @njit(parallel=True, fastmath=False, cache=False, error_model="numpy")
    def classify_many(designs, px, py, tol):
        """Class of every (design, sample) pair (for the self-test)."""
        out = np.zeros((designs.shape[0], px.shape[0]), dtype=np.int64)
        for i in prange(designs.shape[0]):
            for j in range(px.shape[0]):
                out[i, j] = classify(px[j], py[j] + designs[i, 3], designs[i, 0], designs[i, 1],
                                     designs[i, 2], tol)[0]
        return out

    return {"grid_search": grid_search, "design_gii": design_gii, "batch_gii_gdi": batch_gii_gdi,
            "classify_many": classify_many, "numba": numba}


_KERNELS = None


def kernels():
    global _KERNELS
    if _KERNELS is None:
        _KERNELS = build_kernels()
    return _KERNELS


# ----------------------------------------------------------------------------------------------
# numba-grid
# ----------------------------------------------------------------------------------------------

def interleaved_rows(rows, threads):
    """prange splits its range into `threads` contiguous pieces: give each piece every
    threads-th row of the grid, so that each thread sees cheap and costly rows alike."""
    return np.concatenate([np.arange(t, rows, threads) for t in range(threads)]).astype(np.int64)


def run_grid_kernel(study, axes, threads, prune):
    kr = kernels()
    rows = len(axes[0]) * len(axes[1])
    order = interleaved_rows(rows, threads)
    t0 = time.perf_counter()
    best_val, best_idx, counts = kr["grid_search"](axes[0], axes[1], axes[2], axes[3], study.xs, study.ys,
                                                   study.box, study.singularity_tolerance, prune, order)
    seconds = time.perf_counter() - t0
    ok = best_idx >= 0
    if not ok.any():
        return seconds, None, None, counts.sum(axis=0)
    vals = best_val[ok]
    idxs = best_idx[ok]
    top = vals.max()
    index = int(idxs[vals == top].min())  # ties: the first design in grid order
    return seconds, float(top), index, counts.sum(axis=0)


def design_of(axes, index):
    counts = [len(a) for a in axes]
    values = []
    for k in reversed(range(4)):
        values.append(float(axes[k][index % counts[k]]))
        index //= counts[k]
    return list(reversed(values))


def numba_grid(args):
    kr = kernels()
    numba = kr["numba"]
    numba.set_num_threads(args.threads)
    study = Study(args.problem)
    axes = study.axes()
    # Warm-up on a tiny grid (compiles the kernel; JIT time is not measured).
    tiny = [np.ascontiguousarray(a[:: max(1, len(a) // 2)][:2]) for a in axes]
    t0 = time.perf_counter()
    run_grid_kernel(study, tiny, args.threads, args.prune)
    compile_s = time.perf_counter() - t0
    runs = []
    result = None
    for _ in range(args.repeats):
        seconds, value, index, counts = run_grid_kernel(study, axes, args.threads, args.prune)
        runs.append(seconds)
        result = (value, index, counts)
    value, index, counts = result
    out = {
        "peer": "numba-grid", "problem": os.path.relpath(study.path, ROOT), "threads": args.threads,
        "prune": bool(args.prune), "seconds": min(runs), "runs_s": runs, "compile_s": compile_s,
        "best_value": value, "best_index": index,
        "best_design": dict(zip(study.names, design_of(axes, index))) if index is not None else None,
        "designs": int(np.prod([len(a) for a in axes])),
        "feasible": int(counts[0]), "constraint_violated": int(counts[1]), "sample_failed": int(counts[2]),
        "pruned": int(counts[3]), "samples_evaluated": int(counts[4]),
        "numba": numba.__version__, "threading_layer": numba.threading_layer(),
    }
    if args.check:
        out["check"] = check_against(out, args.check)
    print(json.dumps(out), flush=True)
    return 0 if not args.check or out["check"]["passed"] else 1


# ----------------------------------------------------------------------------------------------
# numpy-grid (angle formulas, as hapsyn's fivebar.cpp writes them)
# ----------------------------------------------------------------------------------------------

def np_leg(dx, dy, l1, l2):
    """Vectorised elbow-out IK of one leg: unreachable, on_joint, ux, uy, wx, wy, q_act, q_free."""
    rho2 = dx * dx + dy * dy
    rho = np.sqrt(rho2)
    diff = (l1 - l2) * (l1 + l2)
    spread = l1 * l1 + l2 * l2 + rho2
    positive = rho > 0.0
    den = 2.0 * l1 * rho
    c = (diff + rho2) / den
    tolerance = 8.0 * EPS * spread / den
    near = np.abs(diff) <= 8.0 * EPS * spread
    unreachable = np.where(positive, ~(np.abs(c) <= 1.0 + tolerance), ~near)
    on_joint = ~positive & near
    c = np.clip(c, -1.0, 1.0)
    s = np.sqrt((1.0 - c) * (1.0 + c))
    ex = dx / rho
    ey = dy / rho
    ux = c * ex - s * ey
    uy = c * ey + s * ex
    wx = dx - l1 * ux
    wy = dy - l1 * uy
    q_act = np.arctan2(dy, dx) + np.arccos(c)
    q_free = np.arctan2(wy, wx)
    q_free = np.where(q_free < -0.5 * PI, q_free + 2.0 * PI, q_free)
    return unreachable, on_joint, ux, uy, wx, wy, q_act, q_free


def np_sample(x, y, l0, l1, l2, tol):
    """Vectorised classification and Jacobian (hapsyn's angle-based G): (class, a, b, c, d)."""
    h0 = 0.5 * l0
    ul, jl, u1x, u1y, w1x, w1y, q1, q2 = np_leg(x + h0, y, l1, l2)
    ur, jr, rux, ruy, rwx, rwy, qa_r, qf_r = np_leg(h0 - x, y, l1, l2)
    q3 = PI - qf_r
    q4 = PI - qa_r
    u4x, u4y, w2x, w2y = -rux, ruy, -rwx, rwy
    s12 = (w1x * u1y - w1y * u1x) / l2
    s34 = (rwx * ruy - rwy * rux) / l2
    cross12 = w1x * w2y - w1y * w2x
    s23 = cross12 / (l2 * l2)
    nonsingular = (np.abs(s12) >= tol) & (np.abs(s34) >= tol) & (np.abs(s23) >= tol)
    t = ANGLE_TOL
    mode = q3 - q2
    valid = (q2 >= -t) & (q2 <= q1 + t) & (q3 <= PI + t) & (q4 <= q3 + t) & (mode > 0.0) & (mode < PI)
    cls = np.where(ul | ur, UNREACHABLE,
                   np.where(jl | jr, SINGULAR, np.where(~nonsingular, SINGULAR, np.where(~valid, INVALID, REACHABLE))))
    b1 = l1 * (u1x * w1y - u1y * w1x)
    b2 = l1 * (u4x * w2y - u4y * w2x)
    inv_det = 1.0 / cross12
    return cls, w2y * b1 * inv_det, -w1y * b2 * inv_det, -w2x * b1 * inv_det, w1x * b2 * inv_det


def np_singular_values(a, b, c, d):
    e = 0.5 * (a + d)
    f = 0.5 * (a - d)
    g = 0.5 * (c + b)
    h = 0.5 * (c - b)
    smax = np.sqrt(e * e + h * h) + np.sqrt(f * f + g * g)
    smin = np.where(smax > 0.0, np.abs(a * d - b * c) / smax, 0.0)
    return np.minimum(smin, smax), smax


def numpy_grid_search(study, axes, block=1 << 16):
    """Best GII of the grid: (value, index, counts[feasible, constraint, failed, samples])."""
    counts = np.zeros(4, dtype=np.int64)
    best_value, best_index = -np.inf, -1
    n3 = len(axes[3])
    g0, g1, g2, g3 = np.meshgrid(*axes, indexing="ij")  # grid order: last variable fastest
    l0_all, l1_all, l2_all, r_all = (g.ravel() for g in (g0, g1, g2, g3))
    total = l0_all.size
    xmin, xmax, ymin, ymax = study.box
    tol = study.singularity_tolerance
    with np.errstate(all="ignore"):
        for start in range(0, total, block):
            sl = slice(start, min(start + block, total))
            l0, l1, l2, r = l0_all[sl], l1_all[sl], l2_all[sl], r_all[sl]
            index = np.arange(sl.start, sl.stop)
            h0 = 0.5 * l0
            ay = np.maximum(np.abs(ymin + r), np.abs(ymax + r))
            ax = np.maximum(np.maximum(np.abs(xmin + h0), np.abs(xmax + h0)),
                            np.maximum(np.abs(xmin - h0), np.abs(xmax - h0)))
            s = l1 + l2
            fits = ~((ax * ax + ay * ay) - s * s > 0.0)
            counts[1] += int((~fits).sum())
            l0, l1, l2, r, index = l0[fits], l1[fits], l2[fits], r[fits], index[fits]
            min_smin = np.full(l0.size, np.inf)
            max_smax = np.full(l0.size, -np.inf)
            for x, y in zip(study.xs, study.ys):
                if l0.size == 0:
                    break
                counts[3] += l0.size
                cls, a, b, c, d = np_sample(x, y + r, l0, l1, l2, tol)
                smin, smax = np_singular_values(a, b, c, d)
                ok = cls == REACHABLE
                if not ok.all():  # designs end at their first failing sample
                    counts[2] += int((~ok).sum())
                    l0, l1, l2, r, index = l0[ok], l1[ok], l2[ok], r[ok], index[ok]
                    min_smin, max_smax, smin, smax = min_smin[ok], max_smax[ok], smin[ok], smax[ok]
                np.minimum(min_smin, smin, out=min_smin)
                np.maximum(max_smax, smax, out=max_smax)
            counts[0] += l0.size
            if l0.size:
                gii = np.where((max_smax > 0.0) & np.isfinite(max_smax), min_smin / max_smax, 0.0)
                k = int(np.argmax(gii))  # first of the largest: the lowest grid index
                if gii[k] > best_value:
                    best_value, best_index = float(gii[k]), int(index[k])
    return best_value, best_index, counts


def numpy_grid(args):
    study = Study(args.problem)
    axes = study.axes()
    t0 = time.perf_counter()
    value, index, counts = numpy_grid_search(study, axes)
    seconds = time.perf_counter() - t0
    out = {
        "peer": "numpy-grid", "problem": os.path.relpath(study.path, ROOT), "threads": 1, "prune": False,
        "seconds": seconds, "best_value": value, "best_index": index,
        "best_design": dict(zip(study.names, design_of(axes, index))) if index >= 0 else None,
        "designs": int(np.prod([len(a) for a in axes])), "feasible": int(counts[0]),
        "constraint_violated": int(counts[1]), "sample_failed": int(counts[2]), "samples_evaluated": int(counts[3]),
        "numpy": np.__version__,
    }
    if args.check:
        out["check"] = check_against(out, args.check)
    print(json.dumps(out), flush=True)
    return 0 if not args.check or out["check"]["passed"] else 1


# ----------------------------------------------------------------------------------------------
# The optimum check against hapsyn's result.json
# ----------------------------------------------------------------------------------------------

def check_against(out, result_path, rtol=1e-9):
    with open(result_path) as f:
        result = json.load(f)
    best = result["best"]
    value = best["objectives"][0] if isinstance(best["objectives"], list) else list(best["objectives"].values())[0]
    design = best["design"]
    mine = out["best_design"] or {}
    same_design = all(name in mine and mine[name] == float(design[name]) for name in design)
    close = out["best_value"] is not None and abs(out["best_value"] - value) <= rtol * abs(value)
    check = {"result": result_path, "hapsyn_value": value, "hapsyn_design": design,
             "value_relative_difference": abs(out["best_value"] - value) / abs(value) if out["best_value"] else None,
             "same_design": same_design, "passed": bool(close and same_design)}
    stats = result.get("statistics", {})
    # Counts that do not depend on pruning or threads: designs and reach violations; without
    # pruning on both sides, also the feasible and sample-failed counts.
    for key in ("constraint_violated",) + (("feasible", "sample_failed") if not out["prune"] and
                                          stats.get("prune") is False else ()):
        if key in stats:
            check[key + "_hapsyn"] = stats[key]
            check["passed"] = check["passed"] and stats[key] == out[key]
    return check


# ----------------------------------------------------------------------------------------------
# deap-nsga2
# ----------------------------------------------------------------------------------------------

def hypervolume_2d(points, reference=(0.0, 0.0)):
    """Area dominated by `points` (both objectives maximised) and bounded by `reference`,
    counting only points strictly better than the reference in both (pareto.cpp's rule)."""
    pts = sorted({(float(a), float(b)) for a, b in points if a > reference[0] and b > reference[1]},
                 key=lambda p: (-p[0], -p[1]))
    area, top = 0.0, reference[1]
    for a, b in pts:  # GII descending: each point adds its strip above the best GDI so far
        if b > top:
            area += (a - reference[0]) * (b - top)
            top = b
    return area


def first_front(values):
    """Indices of the non-dominated rows of `values` (maximised), duplicates kept."""
    n = len(values)
    keep = []
    for i in range(n):
        dominated = False
        for j in range(n):
            if j != i and all(values[j] >= values[i]) and any(values[j] > values[i]):
                dominated = True
                break
        if not dominated:
            keep.append(i)
    return keep


def deap_nsga2(args):
    from deap import base, creator, tools
    kr = kernels()
    numba = kr["numba"]
    numba.set_num_threads(args.threads)
    study = Study(args.problem)
    low, up = list(study.lower), list(study.upper)
    consts = study.mass_constants()
    evaluate_batch = kr["batch_gii_gdi"]
    evaluate_batch(np.array([[0.0, 0.2, 0.3, 0.4]]), study.xs, study.ys, study.box, consts)  # JIT warm-up

    if not hasattr(creator, "FiveBarFitness"):
        creator.create("FiveBarFitness", base.Fitness, weights=(1.0, 1.0))
        creator.create("FiveBarIndividual", list, fitness=creator.FiveBarFitness)
    toolbox = base.Toolbox()
    toolbox.register("mate", tools.cxSimulatedBinaryBounded, low=low, up=up, eta=args.eta_c)
    toolbox.register("mutate", tools.mutPolynomialBounded, low=low, up=up, eta=args.eta_m, indpb=args.m)
    toolbox.register("select", tools.selNSGA2, nd=args.nd)
    counters = {"designs": 0, "samples": 0}

    def evaluate(individuals):
        if not individuals:
            return
        status, values, samples, violation = evaluate_batch(np.array(individuals, dtype=np.float64), study.xs,
                                                            study.ys, study.box, consts)
        counters["designs"] += len(individuals)
        counters["samples"] += int(samples.sum())
        for ind, s, v, g in zip(individuals, status, values, violation):
            if s == FEASIBLE:
                ind.fitness.values = (float(v[0]), float(v[1]))
            elif s == CONSTRAINT_VIOLATED:
                ind.fitness.values = (CONSTRAINT_FITNESS - g, CONSTRAINT_FITNESS - g)
            else:
                ind.fitness.values = (SAMPLE_FAILED_FITNESS, SAMPLE_FAILED_FITNESS)

    t0 = time.perf_counter()
    random.seed(args.seed)
    pop = [creator.FiveBarIndividual(random.uniform(a, b) for a, b in zip(low, up)) for _ in range(args.population)]
    evaluate(pop)
    pop = toolbox.select(pop, len(pop))  # assigns the crowding distances the tournament reads
    for _ in range(args.generations):
        offspring = [toolbox.clone(ind) for ind in tools.selTournamentDCD(pop, len(pop))]
        for a, b in zip(offspring[::2], offspring[1::2]):
            if random.random() <= args.cr:
                toolbox.mate(a, b)
            toolbox.mutate(a)
            toolbox.mutate(b)
            del a.fitness.values, b.fitness.values
        evaluate([ind for ind in offspring if not ind.fitness.valid])
        pop = toolbox.select(pop + offspring, args.population)
    seconds = time.perf_counter() - t0

    values = np.array([ind.fitness.values for ind in pop])
    feasible = [i for i in range(len(pop)) if values[i, 0] > SAMPLE_FAILED_FITNESS]
    front_idx = [feasible[i] for i in first_front(values[feasible])] if feasible else []
    seen, front = set(), []
    for i in front_idx:
        key = tuple(pop[i])
        if key not in seen:
            seen.add(key)
            front.append({"design": dict(zip(study.names, pop[i])), "objectives": list(values[i])})
    front.sort(key=lambda p: p["objectives"])
    hv = hypervolume_2d([p["objectives"] for p in front])
    best_gii = max(front, key=lambda p: p["objectives"][0]) if front else None
    out = {
        "peer": "deap-nsga2", "problem": os.path.relpath(study.path, ROOT), "threads": args.threads,
        "population": args.population, "generations": args.generations, "seed": args.seed,
        "parameters": {"cr": args.cr, "eta_c": args.eta_c, "m": args.m, "eta_m": args.eta_m, "nd": args.nd},
        "seconds": seconds, "hypervolume": hv, "reference_point": [0.0, 0.0], "front_points": len(front),
        "best_value": best_gii["objectives"] if best_gii else None,
        "best_design": best_gii["design"] if best_gii else None,
        "designs": counters["designs"], "samples_evaluated": counters["samples"],
        "deap": __import__("deap").__version__, "numba": numba.__version__,
    }
    if args.front_out:
        with open(args.front_out, "w") as f:
            json.dump(front, f)
    print(json.dumps(out), flush=True)
    return 0


# ----------------------------------------------------------------------------------------------
# self-test against hapsyn
# ----------------------------------------------------------------------------------------------

def default_hapsyn():
    return os.environ.get("HAPSYN") or os.path.join(ROOT, "build", "bin", "hapsyn")


def self_test(args):
    kr = kernels()
    kr["numba"].set_num_threads(args.threads)
    study = Study(GRID_PROBLEM)
    consts = study.mass_constants()
    ok = True
    report = {"peer": "self-test"}

    # 1. numba's GII and GDI per design against hapsyn over a 3x3x3x5 grid of designs: one
    #    `hapsyn sweep` over the designs' values, each run the evaluate solver (or, in a build
    #    without it, the grid solver on the one fixed design, unpruned).
    sub = [[0.0, 0.01, 0.1], [0.15, 0.23, 0.3], [0.2, 0.25, 0.3], [0.05, 0.2, 0.3, 0.37, 0.42]]
    listed = subprocess.run([args.hapsyn, "plugins"], capture_output=True, text=True).stdout
    solver = ({"plugin": "evaluate"} if re.search(r"^evaluate\s+solver", listed, re.M)
              else {"plugin": "grid", "options": {"prune": False}})
    problem = {
        "name": "fivebar-peers-self-test",
        "mechanism": study.problem["mechanism"], "scene": study.problem["scene"],
        "design": {v: {"value": sub[i][0]} for i, v in enumerate(study.names)},
        "objectives": [{"metric": "gii", "sense": "maximize"}, {"metric": "gdi", "sense": "maximize"}],
        "solver": solver, "output": {"samples_csv": False}, "seed": 1,
    }
    work = tempfile.mkdtemp(prefix="fivebar-peers-")
    path = os.path.join(work, "problem.json")
    with open(path, "w") as f:
        json.dump(problem, f)
    argv = [args.hapsyn, "sweep", path, "--out", os.path.join(work, "sweep"), "--threads", "1", "--force"]
    for i, v in enumerate(study.names):
        argv += ["--vary", f"design.{v}.value=" + ",".join(repr(x) for x in sub[i])]
    t0 = time.perf_counter()
    p = subprocess.run(argv, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"self-test: {' '.join(argv)} failed:\n{p.stderr[-3000:]}")
    hapsyn_s = time.perf_counter() - t0
    runs = collect_sweep_runs(os.path.join(work, "sweep"))
    shutil.rmtree(work, ignore_errors=True)
    designs = np.array([[run["design"][v] for v in study.names] for run in runs])
    status, values, _, _ = kr["batch_gii_gdi"](designs, study.xs, study.ys, study.box, consts)
    worst, mismatches, tally = 0.0, [], {"feasible": 0, "constraint_violated": 0, "sample_failed": 0}
    for run, s, v in zip(runs, status, values):
        if run["status"] == "converged":
            theirs = FEASIBLE
        elif re.search(r"design constraint '\w+' is violated|[1-9]\d* violate a design constraint", run["message"]):
            theirs = CONSTRAINT_VIOLATED
        else:
            theirs = SAMPLE_FAILED
        if theirs != s:
            mismatches.append({"design": run["design"], "hapsyn": run["status"], "message": run["message"],
                               "numba": int(s)})
            continue
        tally[{FEASIBLE: "feasible", CONSTRAINT_VIOLATED: "constraint_violated",
               SAMPLE_FAILED: "sample_failed"}[theirs]] += 1
        if theirs == FEASIBLE:
            for mine, name in zip(v, ("gii", "gdi")):
                worst = max(worst, abs(mine - run["objectives"][name]) / abs(run["objectives"][name]))
    passed = not mismatches and worst <= 1e-12 and len(runs) == 135 and tally["feasible"] > 0
    ok = ok and passed
    report["per_design"] = {"designs": len(runs), "hapsyn_solver": solver["plugin"], **tally,
                            "max_relative_difference_gii_gdi": worst, "status_mismatches": mismatches[:5],
                            "hapsyn_sweep_s": hapsyn_s, "passed": passed}

    # 2. Trig-free classification (numba) against the angle formulas (numpy) on random designs
    #    over the hard-limit-free default box and samples of the scene plus random points.
    rng = np.random.default_rng(16)
    n = 4000
    designs = np.column_stack([rng.uniform(0.0, 0.3, n), rng.uniform(0.01, 0.3, n), rng.uniform(0.01, 0.3, n),
                               rng.uniform(-0.1, 0.6, n)])
    # Grid values too (exact zeros, coincident joints, equal links).
    axes = study.axes()
    pick = rng.integers(0, [len(a) for a in axes], size=(n, 4))
    designs = np.vstack([designs, np.column_stack([axes[k][pick[:, k]] for k in range(4)])])
    px = np.concatenate([study.xs, rng.uniform(-0.3, 0.3, 200)])
    py = np.concatenate([study.ys, rng.uniform(-0.6, 0.3, 200)])
    fast = kr["classify_many"](designs, px, py, study.singularity_tolerance)
    with np.errstate(all="ignore"):
        slow = np_sample(px[None, :], py[None, :] + designs[:, 3:4], designs[:, 0:1], designs[:, 1:2],
                         designs[:, 2:3], study.singularity_tolerance)[0]
    differ = int((fast != slow).sum())
    histogram = {name: int((slow == c).sum()) for name, c in
                 (("reachable", REACHABLE), ("unreachable", UNREACHABLE), ("singular", SINGULAR), ("invalid", INVALID))}
    report["classification"] = {"pairs": int(fast.size), "classes": histogram, "differing": differ,
                                "passed": differ == 0}
    ok = ok and differ == 0
    report["passed"] = ok
    print(json.dumps(report), flush=True)
    return 0 if ok else 1


def collect_sweep_runs(directory):
    """Design, status and objective values of each run of a hapsyn sweep (its result.json files)."""
    runs = []
    for name in sorted(os.listdir(directory)):
        result_path = os.path.join(directory, name, "result.json")
        if not os.path.isfile(result_path):
            continue
        with open(result_path) as f:
            result = json.load(f)
        design = {k: float(v) for k, v in result["problem"]["design"].items() for v in [v["value"]]}
        objectives = result.get("best", {}).get("objectives")
        runs.append({"design": design, "status": result["status"], "objectives": objectives,
                     "message": result.get("message")})
    return runs


# ----------------------------------------------------------------------------------------------

def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--self-test", action="store_true",
                    help="numba against hapsyn on a small grid (the self-test subcommand with its defaults)")
    sub = ap.add_subparsers(dest="command")
    g = sub.add_parser("numba-grid", help="exhaustive GII grid search, numba")
    g.add_argument("--threads", type=int, default=1)
    g.add_argument("--prune", action="store_true")
    g.add_argument("--repeats", type=int, default=3, help="timed runs; the best is reported")
    g.add_argument("--problem", default=GRID_PROBLEM)
    g.add_argument("--check", metavar="RESULT_JSON", help="hapsyn's result.json of the same grid")
    g.set_defaults(func=numba_grid)
    n = sub.add_parser("numpy-grid", help="exhaustive GII grid search, numpy, one core")
    n.add_argument("--problem", default=GRID_PROBLEM)
    n.add_argument("--check", metavar="RESULT_JSON")
    n.set_defaults(func=numpy_grid)
    d = sub.add_parser("deap-nsga2", help="DEAP NSGA-II, GII and GDI")
    d.add_argument("--population", type=int, default=200)
    d.add_argument("--generations", type=int, default=3000)
    d.add_argument("--seed", type=int, default=1)
    d.add_argument("--threads", type=int, default=1, help="numba threads of the batch evaluation")
    d.add_argument("--cr", type=float, default=0.95)
    d.add_argument("--eta-c", dest="eta_c", type=float, default=10.0)
    d.add_argument("--m", type=float, default=0.01, help="mutation probability per component (pagmo's and "
                                                         "hapsyn's default 0.01)")
    d.add_argument("--eta-m", dest="eta_m", type=float, default=50.0)
    d.add_argument("--nd", choices=["standard", "log"], default="standard", help="selNSGA2's non-dominated sort")
    d.add_argument("--problem", default=NSGA2_PROBLEM)
    d.add_argument("--front-out", help="write the final front (designs, objectives) here")
    d.set_defaults(func=deap_nsga2)
    s = sub.add_parser("self-test", help="numba against hapsyn on a small grid")
    s.add_argument("--hapsyn", default=default_hapsyn())
    s.add_argument("--threads", type=int, default=1)
    s.set_defaults(func=self_test)
    args = ap.parse_args(argv)
    if args.self_test:
        return self_test(ap.parse_args(["self-test"]))
    if not args.command:
        ap.error("a subcommand (or --self-test) is required")
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
