#!/usr/bin/env python3
"""Checks the result of one example study (out_of_tree_test.sh) against values computed here,
independently of hapsyn: from the example's own analytic case, or from another plugin's output.

  check_example.py mean_isotropy OUT            OUT: the run's output directory
  check_example.py planar_disc OUT STUDY SQUARE_OUT
                                                STUDY: the study.json that was run; SQUARE_OUT: the
                                                mean_isotropy run (the same five-bar design)
  check_example.py planar_2r OUT STUDY          STUDY: the study.json that was run
  check_example.py random_search OUT EVALUATED  EVALUATED: its best design run by `evaluate`
  check_example.py fixed_design_study STUDY OUT NEW_STUDY
                                                writes NEW_STUDY: STUDY with the design fixed at
                                                OUT's best and the in-tree `evaluate` solver

Prints what it compared; exits non-zero (AssertionError) on a mismatch.
"""
import csv
import json
import math
import sys


def load_result(out):
    with open(out + "/result.json") as f:
        r = json.load(f)
    return r


def load_samples(out):
    with open(out + "/samples.csv") as f:
        return list(csv.DictReader(f))


def close(a, b, rel):
    return abs(a - b) <= rel * max(abs(a), abs(b))


def expect_status(r, status):
    assert r["status"] == status, "status = %r (expected %r): %s" % (r["status"], status, r.get("message"))


def check_mean_isotropy(out):
    """mean_isotropy against the mean of sigma_min / sigma_max that the in-tree gii wrote per sample
    (its own closed-form singular values), over the samples (all reachable in this study)."""
    r = load_result(out)
    expect_status(r, "converged")
    o = r["best"]["objectives"]
    m, g = o["mean_isotropy"], o["gii"]
    rows = load_samples(out)
    assert all(row["status"] == "reachable" for row in rows), "the study needs every sample reachable"
    ratios = [float(row["gii.sigma_min_J"]) / float(row["gii.sigma_max_J"]) for row in rows]
    expected = sum(ratios) / len(ratios)
    print("mean_isotropy = %.10f, from gii's per-sample singular values %.10f; gii = %.10f, samples = %d"
          % (m, expected, g, r["samples_in_scene"]))
    assert close(m, expected, 1e-8), "mean_isotropy = %r, expected %r" % (m, expected)
    assert 0.0 < g <= m <= 1.0, "expected 0 < gii <= mean_isotropy <= 1: gii = %r, mean_isotropy = %r" % (g, m)
    files = [p["file"] for p in r["plugins"] if p["name"] == "mean_isotropy"]
    assert files and files[0].endswith("/plugins/hapsyn-mean_isotropy.so"), files


def disc_points(radius, step, centre):
    """The disc's samples as planar_disc documents them: centre + (i, j) step, x fastest."""
    ratio = radius / step
    m = int(math.floor(ratio + 1e-9))
    limit = ratio * ratio * (1.0 + 1e-9)
    return [(centre[0] + i * step, centre[1] + j * step, i, j)
            for j in range(-m, m + 1) for i in range(-m, m + 1) if float(i * i + j * j) <= limit]


def check_planar_disc(out, study_file, square_out):
    """The samples are the documented grid points of the disc (count, order, coordinates); the GII of
    the same five-bar design over them equals the GII over those points of the 100 mm square's grid,
    taken from the square run's per-sample singular values."""
    r = load_result(out)
    expect_status(r, "converged")
    with open(study_file) as f:
        scene = json.load(f)["scene"]["options"]
    step = scene["step"]
    points = disc_points(scene["radius"], step, scene["centre"])
    rows = load_samples(out)
    assert r["samples_in_scene"] == len(points) == len(rows), \
        "samples: %r in the scene, %d expected" % (r["samples_in_scene"], len(points))
    for row, (x, y, _, _) in zip(rows, points):
        assert abs(float(row["x"]) - x) <= 1e-12 and abs(float(row["y"]) - y) <= 1e-12, (row, x, y)
    square = {}
    for row in load_samples(square_out):
        key = (round(float(row["x"]) / step), round(float(row["y"]) / step))
        square[key] = (float(row["gii.sigma_min_J"]), float(row["gii.sigma_max_J"]))
    inside = [square[(i, j)] for (_, _, i, j) in points]
    expected = min(s for s, _ in inside) / max(s for _, s in inside)
    gii = r["best"]["objectives"]["gii"]
    print("planar_disc: %d samples as documented; gii = %.10f, over the same points of the square %.10f"
          % (len(points), gii, expected))
    assert close(gii, expected, 1e-8), "gii = %r, expected %r" % (gii, expected)


def arm_gii(l1, l2, points, tolerance):
    """GII of the 2R arm over the points, or None when a point is unreachable or singular (then the
    worst-case design is infeasible). The arm's singular values depend on q2 only:
    J = R(q1) [-l2 s2, -l2 s2; l1 + l2 c2, l2 c2], so |det J| = l1 l2 |s2| and
    ||J||_F^2 = l1^2 + 2 l2^2 + 2 l1 l2 c2; classified as planar_2r documents it."""
    eps = 2.0 ** -52
    lowest, highest = math.inf, 0.0
    for (x, y, _, _) in points:
        r2 = x * x + y * y
        c2 = (r2 - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
        if not abs(c2) <= 1.0 + 8.0 * eps * (r2 + l1 * l1 + l2 * l2) / (2.0 * l1 * l2):
            return None
        c2 = min(1.0, max(-1.0, c2))
        s2 = math.sqrt((1.0 - c2) * (1.0 + c2))
        if s2 < tolerance:
            return None
        frobenius2 = l1 * l1 + 2.0 * l2 * l2 + 2.0 * l1 * l2 * c2
        det = l1 * l2 * s2
        sigma_max = math.sqrt(0.5 * (frobenius2 + math.sqrt(max(0.0, frobenius2 * frobenius2 - 4.0 * det * det))))
        lowest = min(lowest, det / sigma_max)
        highest = max(highest, sigma_max)
    return lowest / highest


def grid_values(spec):
    lower, upper, step = spec["lower"], spec["upper"], spec["step"]
    n = (upper - lower) / step
    count = int(math.floor(n + 1e-9 * max(1.0, n))) + 1  # as DesignSpace::grid_count
    return [min(lower + i * step, upper) for i in range(count)]


def check_planar_2r(out, study_file):
    """The grid optimum of the 2R arm's GII over the disc, found here by brute force over the same
    grid with the closed-form singular values (the first best in grid order, l2 fastest)."""
    r = load_result(out)
    expect_status(r, "converged")
    with open(study_file) as f:
        study = json.load(f)
    scene = study["scene"]["options"]
    points = disc_points(scene["radius"], scene["step"], scene["centre"])
    tolerance = study["mechanism"].get("options", {}).get("singularity_tolerance", 1e-6)
    best = None
    feasible = 0
    for l1 in grid_values(study["design"]["l1"]):
        for l2 in grid_values(study["design"]["l2"]):
            g = arm_gii(l1, l2, points, tolerance)
            if g is None:
                continue
            feasible += 1
            if best is None or g > best[0]:
                best = (g, l1, l2)
    assert best, "no feasible design on the grid"
    design = r["best"]["design"]
    gii = r["best"]["objectives"]["gii"]
    print("planar_2r: hapsyn l1 = %.4f, l2 = %.4f, gii = %.10f; brute force (%d feasible designs) "
          "l1 = %.4f, l2 = %.4f, gii = %.10f" % (design["l1"], design["l2"], gii, feasible, best[1], best[2], best[0]))
    assert abs(design["l1"] - best[1]) <= 1e-12 and abs(design["l2"] - best[2]) <= 1e-12, (design, best)
    assert close(gii, best[0], 1e-9), "gii = %r, expected %r" % (gii, best[0])


def check_random_search(out, evaluated_out):
    """The reported best score is what the in-tree evaluate solver gets for the reported design."""
    r = load_result(out)
    expect_status(r, "budget_exhausted")
    e = load_result(evaluated_out)
    expect_status(e, "converged")
    print("random_search: best score %.12g, evaluated again %.12g" % (r["best"]["score"], e["best"]["score"]))
    assert close(r["best"]["score"], e["best"]["score"], 1e-12), (r["best"], e["best"])


def fixed_design_study(study_file, out, new_study_file):
    with open(study_file) as f:
        study = json.load(f)
    best = load_result(out)["best"]["design"]
    study["design"] = {name: {"value": value} for name, value in best.items()}
    study["solver"] = {"plugin": "evaluate"}
    with open(new_study_file, "w") as f:
        json.dump(study, f, indent=1)


if __name__ == "__main__":
    checks = {"mean_isotropy": check_mean_isotropy, "planar_disc": check_planar_disc,
              "planar_2r": check_planar_2r, "random_search": check_random_search,
              "fixed_design_study": fixed_design_study}
    checks[sys.argv[1]](*sys.argv[2:])
