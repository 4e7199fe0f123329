"""Study.evaluate: one design, a batch, a dict, per-sample records and quantities."""
import csv
import json

import numpy as np
import pytest

import hapsyn
from conftest import PROBLEMS, cli_run, rss_bytes

TABLE2 = PROBLEMS / "fivebar-table2-best-gii.json"
GRID = PROBLEMS / "fivebar-gii-coarse.json"
DESIGN = {"l0": 0.0004, "l1": 0.2997, "l2": 0.3, "r": 0.4196}  # Unal 2008 Table 2, best GII


@pytest.fixture(scope="module")
def study():
    # The Table 2 study with its four lengths free (the grid study's bounds), a 10 mm scene.
    return hapsyn.load(GRID, set=["scene.options.step=0.001", "objectives=[{\"metric\":\"gii\"},{\"metric\":\"gdi\"}]"])


@pytest.fixture(scope="module")
def table2_result(tmp_path_factory):
    return cli_run(TABLE2, tmp_path_factory.mktemp("cli"))


def test_one_design_equals_the_programs_evaluation(study, table2_result):
    e = study.evaluate(DESIGN)
    assert e["status"] == "feasible" and e["feasible"]
    assert e["objectives"] == {"gii": table2_result["best"]["objectives"]["gii"],
                               "gdi": table2_result["best"]["objectives"]["gdi"]}
    assert e["samples_evaluated"] == table2_result["evaluations"]["samples"]
    assert study.free_names == ["l0", "l1", "l2", "r"]
    as_array = study.evaluate(np.array([DESIGN[n] for n in study.free_names]))
    assert as_array["objectives"] == e["objectives"]
    assert study.evaluate([DESIGN[n] for n in study.free_names], threads=2)["objectives"] == e["objectives"]


def test_a_batch_returns_arrays_in_row_order(study):
    rows = np.array([[DESIGN[n] for n in study.free_names],
                     [0.0, 0.01, 0.01, 0.6],         # unreachable workspace
                     [0.1, 0.25, 0.28, 0.40]])
    b = study.evaluate(rows)
    assert b["objectives"].shape == (3, 2) and b["score"].shape == (3,)
    assert b["status"][0] == "feasible" and b["status"][1] in ("constraint_violated", "sample_failed")
    assert np.isnan(b["objectives"][1]).all() and b["score"][1] == -np.inf
    for i in range(3):
        one = study.evaluate(rows[i])
        assert one["status"] == b["status"][i]
        np.testing.assert_array_equal(np.array(list(one["objectives"].values())), b["objectives"][i])


def test_bad_designs_raise_hapsyn_errors(study):
    with pytest.raises(hapsyn.Error, match="4 free values each"):
        study.evaluate([0.1, 0.2])
    with pytest.raises(hapsyn.Error, match=r"problem: design component l1 = 2 from the solver: must lie within the bounds"):
        study.evaluate([0.0, 2.0, 0.2, 0.3])
    with pytest.raises(hapsyn.Error, match="must be finite"):
        study.evaluate([0.0, np.nan, 0.2, 0.3])
    with pytest.raises(hapsyn.Error, match=r"python: design.l3: unknown design variable \(did you mean 'l0'\?\)"):
        study.evaluate({"l0": 0, "l1": 0.2, "l2": 0.2, "r": 0.3, "l3": 1})
    with pytest.raises(hapsyn.Error, match="python: design.r: missing"):
        study.evaluate({"l0": 0, "l1": 0.2, "l2": 0.2})
    # A NaN in a dict once surfaced as the json module's "Out of range float values".
    with pytest.raises(hapsyn.Error, match=r"^python: design.l1 = nan: must be finite$"):
        study.evaluate({"l0": 0, "l1": float("nan"), "l2": 0.2, "r": 0.3})
    # Arguments out of range once surfaced as pybind11's "incompatible function arguments".
    for threads in (2**40, 0, -1, 2.5, True):
        with pytest.raises(hapsyn.Error, match=r"^python: threads = .*: must be an integer from 1 to 1024$"):
            study.evaluate(DESIGN, threads=threads)
    with pytest.raises(hapsyn.Error, match=r"^python: quantities = 'jacobian': must be a list of names"):
        study.evaluate(DESIGN, quantities="jacobian")


def test_a_fixed_variable_in_a_dict_is_checked_not_dropped():
    # Its value was silently dropped (a red-team finding): a study fixing r at 0.42 evaluated
    # {"r": 0.3} at 0.42. Its own value is accepted, so a whole design from a result.json works.
    fixed = hapsyn.load(GRID, set=["scene.options.step=0.002", "design.r={\"value\": 0.42}"])
    assert fixed.free_names == ["l0", "l1", "l2"]
    same = fixed.evaluate({"l0": 0.0, "l1": 0.3, "l2": 0.3, "r": 0.42})
    assert same["objectives"] == fixed.evaluate({"l0": 0.0, "l1": 0.3, "l2": 0.3})["objectives"]
    with pytest.raises(hapsyn.Error, match=r"^python: design.r = 0.3: this study fixes it at 0.42 \(give it that value "
                                           r"or leave it out; free it in the problem's design section to vary it\)$"):
        fixed.evaluate({"l0": 0.0, "l1": 0.3, "l2": 0.3, "r": 0.3})


def test_run_arguments_out_of_range_are_named(study):
    for seed in (-1, 2**70, 1.5):
        with pytest.raises(hapsyn.Error, match=r"^python: seed = .*: must be an integer from 0 to 18446744073709551615$"):
            study.run(seed=seed)
    with pytest.raises(hapsyn.Error, match=r"^python: threads = 8589934592: must be an integer from 0 to 1024$"):
        study.run(threads=2**33)


def test_per_sample_records_equal_the_programs_samples_csv(tmp_path):
    study = hapsyn.load(TABLE2, set=["scene.options.step=0.005"])
    doc = cli_run(TABLE2, tmp_path, "scene.options.step=0.005")
    e = study.evaluate([], samples=True)
    with open(tmp_path / "samples.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(study.scene) == len(e["sample_status"])
    assert e["local_names"] == study.local_names
    assert list(e["sample_status"]) == [r["status"] for r in rows]
    for i, r in enumerate(rows):
        for j, name in enumerate(e["local_names"]):
            assert e["locals"][i, j] == pytest.approx(float(r[name]), rel=1e-9, abs=1e-12)
    assert e["objectives"] == doc["best"]["objectives"]


def test_quantities_are_per_sample_arrays_that_reproduce_the_metric(study):
    e = study.evaluate(DESIGN, quantities=["jacobian", "inertia", "effective_mass"])
    q = e["quantities"]
    n = len(study.scene)
    assert q["jacobian"].shape == (n, 2, 2) and q["inertia"].shape == (n, 2, 2)
    assert q["effective_mass"].shape == (n, 2, 2) and q["q"].shape[0] == n
    assert (e["sample_status"] == "reachable").all()
    s = np.linalg.svd(q["jacobian"], compute_uv=False)
    gii = s[:, 1].min() / s[:, 0].max()
    assert gii == pytest.approx(e["objectives"]["gii"], rel=1e-12)
    assert np.allclose(q["inertia"], np.transpose(q["inertia"], (0, 2, 1)))  # symmetric
    with pytest.raises(hapsyn.Error, match=r"python: quantities\[0\] = \"jacobians\": unknown quantity"):
        study.evaluate(DESIGN, quantities=["jacobians"])
    with pytest.raises(hapsyn.Error, match="^python: quantities: the mechanism 'fivebar' does not provide gravity$"):
        study.evaluate(DESIGN, quantities=["jacobian", "gravity"])
    with pytest.raises(hapsyn.Error, match="^python: quantities: the mechanism 'fivebar' does not provide joint_velocity, "
                                           "velocity_torque$"):  # known names, not provided by the five-bar
        study.evaluate(DESIGN, quantities=["joint_velocity", "velocity_torque"])
    with pytest.raises(hapsyn.Error, match="need one design"):
        study.evaluate(np.zeros((2, 4)), samples=True)


def test_a_thousand_evaluations_do_not_leak():
    study = hapsyn.load(TABLE2, set=["scene.options.step=0.01"])
    design = np.array([])
    for _ in range(200):  # warm-up: allocator pools, first-call caches
        study.evaluate(design)
        study.evaluate(design, samples=True)
    before = rss_bytes()
    for _ in range(1000):
        study.evaluate(design)
        study.evaluate(design, samples=True)
        study.evaluate(np.zeros((3, 0)))
    grown = rss_bytes() - before
    assert grown < 1 << 20, f"RSS grew by {grown} bytes over 1000 evaluate calls"
