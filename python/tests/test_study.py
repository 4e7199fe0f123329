"""load, run, Result, scene, plugins and describe against the hapsyn program."""
import json
import math
import pathlib

import numpy as np
import pytest

import hapsyn
from conftest import PROBLEMS, cli, cli_error, cli_run

TABLE2 = PROBLEMS / "fivebar-table2-best-gii.json"
CULLING = PROBLEMS / "fivebar-gii-culling-coarse.json"


def test_plugins_lists_every_kind_with_its_fields():
    found = hapsyn.plugins()
    by_name = {p["name"]: p for p in found}
    for name, kind in [("fivebar", "mechanism"), ("planar_square", "scene"), ("gii", "metric"), ("culling", "solver")]:
        assert by_name[name]["kind"] == kind
        assert by_name[name]["version"] and by_name[name]["description"]
    _, out, _ = cli("plugins")
    for p in found:
        assert p["name"] in out


def test_describe_is_the_programs_schema():
    _, out, _ = cli("describe", "culling", "--json")
    assert hapsyn.describe("culling") == json.loads(out)
    with pytest.raises(hapsyn.Error) as e:
        hapsyn.describe("culing")
    assert str(e.value) == cli_error("describe", "culing")


def test_load_from_a_file_and_from_a_dict_agree():
    from_file = hapsyn.load(TABLE2)
    with open(TABLE2) as f:
        from_dict = hapsyn.load(json.load(f))
    assert from_file.resolved == from_dict.resolved
    assert from_file.objective_names == ["gii", "gdi"]
    assert from_file.dimension == 0


def test_overrides_apply_in_order():
    study = hapsyn.load(TABLE2, set=["scene.options.step=0.02", "scene.options.step=0.01", "threads=1"])
    assert study.resolved["scene"]["options"]["step"] == 0.01
    assert study.resolved["threads"] == 1
    assert len(study.scene) == 121


@pytest.mark.parametrize("sets", [
    ["design.l1.upper=-3"],
    ["mechanism.plugin=fivebarr"],
    ["solver.plugin=gii"],
    ["scene.options.stpe=0.01"],
    ["objectives[0].sense=up"],
    ["objectives.0=3"],
    ["a..b=1"],
])
def test_errors_are_hapsyn_errors_with_the_programs_message(sets):
    with pytest.raises(hapsyn.Error) as e:
        hapsyn.load(CULLING, set=sets)
    args = ["validate", CULLING]
    for s in sets:
        args += ["--set", s]
    assert str(e.value) == cli_error(*args)
    assert isinstance(e.value, ValueError)


def test_malformed_files_give_the_programs_message(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"name": "x",\n  "mechanism": }\n')
    with pytest.raises(hapsyn.Error) as e:
        hapsyn.load(bad)
    assert str(e.value) == cli_error("validate", bad)
    with pytest.raises(hapsyn.Error) as e:
        hapsyn.load(tmp_path / "missing.json")
    assert str(e.value) == cli_error("validate", tmp_path / "missing.json")


def _same_result(py, doc):
    assert py["status"] == doc["status"]
    assert py["message"] == doc["message"]
    assert py["best"] == doc["best"]
    assert py.get("front") == doc.get("front")
    assert py["evaluations"] == doc["evaluations"]
    assert py["problem"] == doc["problem"]
    assert py["seed"] == doc["seed"]
    assert py["statistics"].keys() == doc["statistics"].keys()


@pytest.mark.parametrize("problem", [TABLE2, CULLING])
def test_run_gives_the_programs_result(problem, tmp_path):
    # One thread: culling's statistics (designs culled per critical sample) depend on the
    # interleaving of its threads, its optimum does not.
    doc = cli_run(problem, tmp_path / "cli", "threads=1", "seed=5")
    result = hapsyn.load(problem, set=["threads=1", "seed=5"]).run(out=tmp_path / "py")
    _same_result(result.to_dict(), doc)
    assert result.status == doc["status"]
    assert result.best_design == doc["best"]["design"]
    assert result.best_objectives == doc["best"]["objectives"]
    assert result.statistics == json.loads(json.dumps(result.to_dict()["statistics"]))
    assert result.info["seed"] == doc["seed"] == 5 and result.info["threads"] == 1
    # The same files as the program's run: result.json (identical up to times), samples.csv.
    py_dir = pathlib.Path(result.output_directory)
    assert (py_dir / "samples.csv").read_text() == (tmp_path / "cli" / "samples.csv").read_text()
    with open(py_dir / "result.json") as f:
        assert json.load(f) == result.to_dict()


# The grid solver writes a progress line every progress_interval seconds.
PROGRESS = ["threads=1", "solver.options.progress_interval=0.01", "solver.options.prune=false",
            "scene.options.step=0.01", "design.l0.step=0.02", "design.r.step=0.02"]


def test_run_without_out_uses_a_temporary_directory_and_reports_progress():
    lines = []
    result = hapsyn.load(PROBLEMS / "fivebar-gii-coarse.json", set=PROGRESS).run(progress=lines.append, seed=1)
    assert result.status == "converged" and result.output_directory is None
    assert lines and all(isinstance(line, str) and "\n" not in line for line in lines)
    assert any("designs" in line for line in lines), lines
    assert result.best_objectives["gii"] > 0.4
    assert result.front is None and result.front_designs is None


def test_a_failing_progress_callback_stops_the_run_and_raises():
    def progress(line):
        raise RuntimeError("callback failed")

    with pytest.raises(RuntimeError, match="callback failed"):
        hapsyn.load(PROBLEMS / "fivebar-gii-coarse.json", set=PROGRESS).run(progress=progress)


def _pareto_problem():
    with open(PROBLEMS / "fivebar-gii-coarse.json") as f:
        problem = json.load(f)
    problem["design"] = {"l0": {"value": 0.0}, "l1": {"lower": 0.2, "upper": 0.3, "step": 0.02},
                         "l2": {"value": 0.3}, "r": {"lower": 0.3, "upper": 0.5, "step": 0.02}}
    problem["objectives"] = [{"metric": "gii"}, {"metric": "gdi"}]
    problem["solver"]["options"]["pareto"] = True
    problem["scene"]["options"]["step"] = 0.02
    return problem


def test_front_as_arrays_equals_the_programs_front(tmp_path):
    problem = _pareto_problem()
    path = tmp_path / "pareto.json"
    path.write_text(json.dumps(problem))
    doc = cli_run(path, tmp_path / "cli")
    result = hapsyn.load(problem).run()
    assert doc["front"] and result.to_dict()["front"] == doc["front"]
    assert result.front.shape == (len(doc["front"]), 2)
    assert result.front_designs.shape == (len(doc["front"]), 2)
    assert result.free_names == ["l1", "r"]
    for row, d, point in zip(result.front, result.front_designs, doc["front"]):
        assert list(row) == [point["objectives"]["gii"], point["objectives"]["gdi"]]
        assert list(d) == [point["design"]["l1"], point["design"]["r"]]
    try:
        import pandas  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="needs pandas"):
            result.to_pandas()
    else:
        frame = result.to_pandas()
        assert list(frame.columns) == ["l1", "r", "gii", "gdi"] and len(frame) == len(doc["front"])


def test_scene_is_a_zero_copy_view_that_keeps_the_study_alive():
    study = hapsyn.load(TABLE2, set=["scene.options.step=0.01"])
    scene = study.scene
    samples = scene.samples
    assert samples.shape == (121, 2) and scene.coordinates == ["x", "y"]
    assert not samples.flags.writeable and not samples.flags.owndata
    assert study.scene.samples.__array_interface__["data"][0] == samples.__array_interface__["data"][0]
    first = samples.copy()
    del study, scene
    import gc
    gc.collect()
    np.testing.assert_array_equal(samples, first)  # still valid: the view owns the study
    assert math.isclose(samples[:, 0].max() - samples[:, 0].min(), 0.1)


def test_version_and_registered_metrics():
    assert hapsyn.version() == hapsyn.__version__ and hapsyn.__version__.count(".") == 2
    assert hapsyn.Error.__mro__[1] is ValueError

    class M:
        locals = [("v", "min", "")]
        needs = []

        def local_batch(self, q):
            return np.ones(len(q["status"]))

    hapsyn.register_metric("py_one", M)
    try:
        assert hapsyn.registered_metrics()["py_one"] is M
        study = hapsyn.load(TABLE2, set=['objectives=[{"metric": "py_one"}]', "scene.options.step=0.01"])
        assert study.evaluate([])["objectives"] == {"py_one": 1.0}
    finally:
        hapsyn.unregister_metric("py_one")
    assert "py_one" not in hapsyn.registered_metrics()
    with pytest.raises(TypeError, match="has no 'locals'"):
        hapsyn.register_metric("bad", object())
