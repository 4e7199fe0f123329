"""Metrics written in Python: equal to their C++ twins, batched, errors."""
import json

import numpy as np
import pytest

import hapsyn
from conftest import PROBLEMS, PyGII, PyMeanIsotropy

GRID = PROBLEMS / "fivebar-gii-coarse.json"
CULLING = PROBLEMS / "fivebar-gii-culling-coarse.json"


def _example_study():
    with open(hapsyn_example()) as f:
        return json.load(f)


def hapsyn_example():
    from conftest import SOURCE_DIR
    return SOURCE_DIR / "examples" / "mean_isotropy" / "study.json"


@pytest.mark.parametrize("exponent", [1.0, 2.5])
def test_python_mean_isotropy_equals_the_cpp_example(plugin_dir, exponent):
    problem = _example_study()
    problem["scene"]["options"]["step"] = 0.002
    problem["objectives"] = [{"metric": "mean_isotropy", "options": {"exponent": exponent}},
                             {"metric": "py_mean_isotropy", "options": {"exponent": exponent}}]
    study = hapsyn.load(problem, plugin_path=plugin_dir, metrics={"py_mean_isotropy": PyMeanIsotropy})
    result = study.run(threads=2)
    cpp, py = result.best_objectives["mean_isotropy"], result.best_objectives["py_mean_isotropy"]
    assert 0.5 < cpp < 1.0
    assert abs(py - cpp) <= 1e-12
    plugins = {p["name"]: p for p in result.to_dict()["plugins"]}
    assert plugins["py_mean_isotropy"]["version"] == "python"
    assert plugins["py_mean_isotropy"]["file"].startswith("python:")


def test_python_metric_over_designs_and_threads_equals_the_cpp_twin(plugin_dir):
    problem = json.loads(GRID.read_text())
    problem["objectives"] = [{"metric": "mean_isotropy"}, {"metric": "py_mean_isotropy"}]
    hapsyn.register_metric("py_mean_isotropy", PyMeanIsotropy)
    try:
        study = hapsyn.load(problem, plugin_path=plugin_dir)
    finally:
        hapsyn.unregister_metric("py_mean_isotropy")
    rng = np.random.default_rng(1)
    designs = np.column_stack([rng.uniform(0, 0.3, 50), rng.uniform(0.01, 0.3, 50), rng.uniform(0.01, 0.3, 50),
                               rng.uniform(0, 0.6, 50)])
    for threads in (1, 3):
        b = study.evaluate(designs, threads=threads)
        feasible = np.array(b["status"]) == "feasible"  # the rest violate the five-bar's constraints
        assert feasible.sum() > 10
        np.testing.assert_allclose(b["objectives"][feasible, 1], b["objectives"][feasible, 0], rtol=0, atol=1e-12)
        assert np.isnan(b["objectives"][~feasible]).all()
    assert (b["objectives"][feasible, 0] > 0).sum() > 10


def test_local_batch_is_called_once_per_chunk():
    problem = _example_study()
    problem["objectives"] = [{"metric": "py"}]
    metric = PyMeanIsotropy()
    study = hapsyn.load(problem, metrics={"py": metric})
    n = len(study.scene)
    study.evaluate([])
    assert metric.calls == 1 and metric.samples_seen == n
    metric.batch_size = 50
    study = hapsyn.load(problem, metrics={"py": metric})
    metric.calls = metric.samples_seen = 0
    e = study.evaluate([], samples=True)
    assert metric.calls >= -(-n // 50) and metric.samples_seen >= n
    reachable = e["sample_status"] == "reachable"
    np.testing.assert_array_equal(e["locals"][:, 1], reachable.astype(float))


@pytest.mark.parametrize("polish", [False, True])
def test_a_worst_case_python_metric_equals_gii_under_culling(polish):
    # Culling prunes with partial (batched) reductions of the worst-case Python metric.
    sets = ["threads=1", f"solver.options.polish={json.dumps(polish)}"]
    cpp = hapsyn.load(CULLING, set=sets).run()
    problem = json.loads(CULLING.read_text())
    problem["objectives"] = [{"metric": "py_gii", "name": "gii"}]
    py = hapsyn.load(problem, set=sets, metrics={"py_gii": PyGII()}).run()
    assert py.status == cpp.status == "converged"
    assert abs(py.best_objectives["gii"] - cpp.best_objectives["gii"]) <= 1e-12
    if not polish:  # the grid optimum: the same design exactly
        assert py.best_design == cpp.best_design
    else:  # SQP from the same grid optimum, on values that differ in the last bits (NumPy's SVD)
        for name, value in cpp.best_design.items():
            assert abs(py.best_design[name] - value) <= 1e-9


def test_python_metric_errors():
    problem = _example_study()
    problem["objectives"] = [{"metric": "py"}]

    class WrongShape(PyMeanIsotropy):
        def local_batch(self, q):
            return np.zeros((q["status"].shape[0], 3))

    with pytest.raises(hapsyn.Error, match=r"^py: local_batch returned shape \(121, 3\) for 121 samples: must be \(121, 2\)$"):
        hapsyn.load(problem, metrics={"py": WrongShape}).evaluate([])

    class Raises(PyMeanIsotropy):
        def local_batch(self, q):
            raise ZeroDivisionError("inside the metric")

    with pytest.raises(ZeroDivisionError, match="inside the metric"):
        hapsyn.load(problem, metrics={"py": Raises}).evaluate([])
    with pytest.raises(ZeroDivisionError, match="inside the metric"):
        hapsyn.load(problem, metrics={"py": Raises}).run()
    with pytest.raises(ZeroDivisionError, match="inside the metric"):  # raised on a worker thread
        hapsyn.load(problem, metrics={"py": Raises}).evaluate([], threads=3)

    class BadReduction(PyMeanIsotropy):
        locals = [("isotropy", "mean", "")]

    with pytest.raises(hapsyn.Error, match=r'objectives\[0\].locals\[0\].reduction = "mean": must be one of'):
        hapsyn.load(problem, metrics={"py": BadReduction})

    problem["objectives"][0]["options"] = {"exponentt": 2}
    with pytest.raises(hapsyn.Error, match=r"problem: objectives\[0\].options = .*exponentt"):
        hapsyn.load(problem, metrics={"py": PyMeanIsotropy})
    with pytest.raises(hapsyn.Error, match="takes no options"):
        hapsyn.load(problem, metrics={"py": PyMeanIsotropy()})

    class NaNs(PyMeanIsotropy):
        def local_batch(self, q):
            return np.full((q["status"].shape[0], 2), np.nan)

    problem["objectives"][0].pop("options")
    with pytest.raises(hapsyn.Error, match=r"problem: metric 'py' returned nan for local value 0 at sample"):
        hapsyn.load(problem, metrics={"py": NaNs}).evaluate([])


def test_a_metric_that_re_enters_its_own_study_is_refused_not_deadlocked(plugin_dir):
    # Issue 53, cause 7: the callback is part of the evaluation it would wait for.
    problem = _example_study()
    problem["objectives"] = [{"metric": "py"}]
    studies = []

    class ReEnters(PyMeanIsotropy):
        def local_batch(self, q):
            studies[0].evaluate([])
            return super().local_batch(q)

    study = hapsyn.load(problem, metrics={"py": ReEnters})
    studies.append(study)
    refused = r"^python: Study.evaluate\(\) called from inside a callback of one of this study's own Python metrics"
    for threads in (1, 3):
        with pytest.raises(hapsyn.Error, match=refused):
            study.evaluate([], threads=threads)
    with pytest.raises(hapsyn.Error, match=refused):
        study.run(threads=2)

    # Another study may be evaluated from inside a callback: it is not waiting for this one.
    other = hapsyn.load(_example_study(), plugin_path=plugin_dir)
    expected = other.evaluate([])["score"]
    seen = []

    class EvaluatesAnother(PyMeanIsotropy):
        def local_batch(self, q):
            seen.append(other.evaluate([])["score"])
            return super().local_batch(q)

    hapsyn.load(problem, metrics={"py": EvaluatesAnother}).evaluate([])
    assert seen and all(s == expected for s in seen)


def test_declarations_and_returns_of_the_wrong_type_are_named():
    # Issue 53, cause 7: these once raised pybind11's bare "Unable to cast Python instance".
    problem = _example_study()
    problem["objectives"] = [{"metric": "py"}]

    def declared(**attributes):
        return type("Declared", (PyMeanIsotropy,), attributes)

    cases = [
        (declared(locals=[("isotropy", 3, "")]), r"^problem: objectives\[0\].locals\[0\].reduction = 3 \(int\): must be a string$"),
        (declared(locals=["isotropy"]), r"^problem: objectives\[0\].locals\[0\] = 'isotropy' \(str\): must be a tuple"),
        (declared(locals=5), r"^problem: objectives\[0\].locals = 5 \(int\): must be a list of \(name, reduction\[, unit\]\)$"),
        (declared(needs="jacobian"), r"^problem: objectives\[0\].needs = 'jacobian' \(str\): must be a list of quantity names$"),
        (declared(needs=[1]), r"^problem: objectives\[0\].needs\[0\] = 1 \(int\): must be a quantity name \(a string\)$"),
        (declared(batch_size="8"), r"^problem: objectives\[0\].batch_size = '8' \(str\): must be an integer >= 1$"),
        (declared(batch_size=True), r"^problem: objectives\[0\].batch_size = True \(bool\): must be an integer >= 1$"),
        (declared(scene_attributes=[1]), r"^problem: objectives\[0\].scene_attributes = \[1\] \(list\): must be a list of strings$"),
        (declared(local_batch=3), r"^problem: objectives\[0\].local_batch = 3 \(int\): must be a method$"),
    ]
    for cls, message in cases:
        with pytest.raises(hapsyn.Error, match=message):
            hapsyn.load(problem, metrics={"py": cls})

    returns = [
        (declared(local_batch=lambda self, q: "abc"), r"^py: local_batch returned 'abc' \(str\), not an array of numbers, for 121"),
        (declared(local_batch=lambda self, q: None), r"^py: local_batch returned None \(NoneType\), not an array of numbers, for 121"),
        (declared(combine=lambda self, r, n: "x"), r"^py: combine returned 'x' \(str\): must be a number$"),
        (declared(combine=lambda self, r, n: None), r"^py: combine returned None \(NoneType\): must be a number$"),
        (declared(combine=lambda self, r, n: 10 ** 400), r"^py: combine returned 1000.* \(int\): must be a number a double can hold"),
        (declared(combine=lambda self, r, n: np.array([0.5, 0.5])), r"^py: combine returned array\(\[0.5, 0.5\]\) \(ndarray\): must be"),
    ]
    for cls, message in returns:
        with pytest.raises(hapsyn.Error, match=message):
            hapsyn.load(problem, metrics={"py": cls}).evaluate([])


def test_a_python_metric_may_not_take_a_plugins_name(plugin_dir):
    # It replaced the built-in gii without a word (a red-team finding).
    problem = _example_study()
    problem["objectives"] = [{"metric": "mean_isotropy"}]
    with pytest.raises(hapsyn.Error, match=r"^problem: objectives\[0\].metric = \"mean_isotropy\": a metric given in "
                                           r"Python \(python:.*\) has the name of the plugin mean_isotropy; register it "
                                           r"under another name$"):
        hapsyn.load(problem, plugin_path=plugin_dir, metrics={"mean_isotropy": PyMeanIsotropy})


def test_local_names_that_would_break_csv_columns_are_refused():
    problem = _example_study()
    problem["objectives"] = [{"metric": "py"}]
    for bad in ["a,b", 'a"b', "a\nb", ""]:
        cls = type("Named", (PyMeanIsotropy,), {"locals": [(bad, "sum", ""), ("reachable", "sum", "")]})
        with pytest.raises(hapsyn.Error, match=r"^problem: objectives\[0\].locals\[0\].name = .*: must be non-empty, "
                                               r"without a comma, a double quote or a line break"):
            hapsyn.load(problem, metrics={"py": cls})
