"""The nonlinear-dynamics analyses against systems with known behaviour: the forced
double-well Duffing oscillator x'' + 0.3 x' - x + x^3 = gamma cos 1.2 t (the parameter set of
Jordan & Smith, Nonlinear Ordinary Differential Equations [JordanSmith2007], whose attractors are period 1 at
gamma = 0.20, period 2 at 0.28, period 4 at 0.29, chaotic at 0.50), Liouville's formula for
its Floquet multipliers, and the ideal slider-crank (one Poincare point); the CLI's sweeps,
cache and bad input."""

import json
import math

import numpy as np
import pytest
from conftest import ROOT, main_in_child, pinbore
from scipy.integrate import solve_ivp

from pinbore.core import sweep
from pinbore.reduced.dynamics import flow, studies

FLORES = ROOT / "scenes" / "reduced" / "slider_crank_flores2004.toml"
DAMPING, FREQUENCY = 0.3, 1.2


class Duffing:
    """The forced Duffing oscillator as a Flow (state: (x, x'), periods elapsed)."""

    def __init__(self, gamma):
        self.gamma = gamma
        self.period = 2 * math.pi / FREQUENCY

    def start(self):
        return np.array([1.0, 0.0]), 0

    def advance(self, state, periods=1):
        y, k = state
        t0 = k * self.period
        sol = solve_ivp(lambda t, z: [z[1], -DAMPING * z[1] + z[0] - z[0] ** 3
                                      + self.gamma * math.cos(FREQUENCY * t)],
                        (t0, t0 + periods * self.period), y, method="DOP853", rtol=1e-11, atol=1e-12)
        return sol.y[:, -1], k + periods

    def coordinates(self, state):
        return state[0].copy()

    def perturb(self, state, dx):
        return state[0] + dx, state[1]


def duffing_sweep(values, cache, **where) -> list[dict]:
    """duffing_point at every value through the sweep engine (core.sweep.run), cached in
    `cache`; `where`: workers or scheduler."""
    options = sweep.Runner(out=cache.parent / "out", cache=cache, **where)
    keys = sweep.point_keys("duffing", [{"gamma": g} for g in values], [], "")
    return sweep.run(duffing_point, values, keys, options)[0]


def duffing_point(gamma):
    """A sweep task (module level, so that worker processes can run it)."""
    duffing = Duffing(gamma)
    samples, states = flow.poincare(duffing, duffing.start(), 200, 64)
    exponent, _ = flow.lyapunov(duffing, states[-1], 150)
    kind, period = flow.classify(samples, exponent)
    return {"value": gamma, "kind": kind, "period": period, "lyapunov_per_s": exponent}


@pytest.mark.parametrize("gamma, kind, period", [(0.20, "periodic", 1), (0.28, "periodic", 2),
                                                 (0.29, "periodic", 4), (0.50, "chaotic", None)])
def test_duffing_attractors_and_the_sign_of_their_exponent(gamma, kind, period):
    point = duffing_point(gamma)
    assert (point["kind"], point["period"]) == (kind, period)
    assert (point["lyapunov_per_s"] > 0) == (kind == "chaotic")
    duffing = Duffing(gamma)
    assert flow.disagreement(kind, point["lyapunov_per_s"], duffing.period) is None


def test_repeating_samples_beside_a_growing_exponent_are_reported():
    """A periodic attractor's largest exponent is negative: samples that repeat beside an
    exponent of +699 1/s at a 12 ms drive period (8 e-folds a period) contradict each other,
    and the summary says so; a small positive estimate (finite-time noise) and the other
    classes do not."""
    assert "+699" in flow.disagreement("periodic", 699.0, 0.012)
    assert flow.disagreement("periodic", 1.0, 0.012) is None
    assert flow.disagreement("periodic", None, 0.012) is None
    assert flow.disagreement("chaotic", 699.0, 0.012) is None


def test_a_parallel_sweep_finds_the_period_doubling_and_resumes_from_its_cache(tmp_path):
    """Between the published period-1 (0.20) and period-2 (0.28) attractors the sweep finds
    one period doubling, where the exponent approaches zero from below; a second run reads
    every point from the cache."""
    values = [0.24, 0.25, 0.26, 0.27, 0.28]
    rows = duffing_sweep(values, tmp_path, workers=2)
    periods = [r["period"] for r in rows]
    first_two = periods.index(2)
    assert periods[:first_two] == [1] * first_two and set(periods[first_two:]) == {2}
    gamma_pd = 0.5 * (values[first_two - 1] + values[first_two])
    assert 0.20 < gamma_pd < 0.28
    exponents = [r["lyapunov_per_s"] for r in rows]
    assert max(exponents[:first_two]) == exponents[first_two - 1] < 0   # rising towards the doubling
    stamps = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
    assert duffing_sweep(values, tmp_path, workers=2) == rows
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == stamps


def test_shooting_finds_the_period_one_orbit_and_liouville_fixes_its_multipliers():
    """Newton on P(x) = x from a rough guess converges quadratically; the multipliers lie in
    the unit circle and their product is det DP = exp(-damping T) (Liouville: the flow's
    divergence is -damping); doubling the difference step moves the largest by less than
    1e-6 (measured 6e-8: central differences of a smooth map, their error O(h^2))."""
    duffing = Duffing(0.20)
    guess = duffing.advance(duffing.start(), 10)
    orbit, multipliers, history, spread = flow.shooting(duffing, guess)
    assert history[-1] <= 1e-9 * (1.0 + np.linalg.norm(orbit[0])) and len(history) <= 8
    assert spread < 1e-6   # a smooth map: its multipliers do not move with the difference step
    assert np.all(np.abs(multipliers) < 1)
    assert np.prod(multipliers).real == pytest.approx(math.exp(-DAMPING * duffing.period), rel=1e-5)
    assert np.allclose(duffing.advance(orbit)[0], orbit[0], atol=1e-8)


def test_ideal_slider_crank_has_one_poincare_point_and_no_positive_exponent(tmp_path):
    scene = tmp_path / "ideal.toml"
    scene.write_text((ROOT / "scenes" / "reduced" / "slider_crank_flores2004_ideal.toml").read_text())
    done = pinbore("dynamics", scene, "--analysis", "poincare", "--transient", "5", "--periods", "8",
                   "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["kind"] == "periodic" and summary["period"] == 1
    assert summary["lyapunov_per_s"] is None or summary["lyapunov_per_s"] <= 0
    samples = np.loadtxt(tmp_path / "out" / "poincare.csv", delimiter=",", skiprows=1)
    assert np.ptp(samples[:, 1:3], axis=0).max() < 1e-12


def test_bifurcation_over_clearance_writes_its_diagram(tmp_path):
    done = pinbore("dynamics", FLORES, "--analysis", "bifurcation", "--parameter", "clearance",
                   "--range", "2e-4", "5e-4", "--points", "2", "--transient", "3", "--periods", "4",
                   "--workers", "2", "--out", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    assert {"bifurcation.csv", "bifurcation.png", "summary.json"} <= {p.name for p in (tmp_path / "out").iterdir()}
    assert sum(json.loads((tmp_path / "out" / "summary.json").read_text())["counts"].values()) == 2


def speed_sweep(parameter, out, cache):
    """A two-point bifurcation sweep of the Flores slider-crank's drive speed named
    `parameter`: its summary.json and its bifurcation.csv."""
    done = pinbore("dynamics", FLORES, "--analysis", "bifurcation", "--parameter", parameter,
                   "--range", "3000", "5000", "--points", "2", "--transient", "3", "--periods", "4",
                   "--workers", "2", "--out", out, "--cache", cache)
    assert done.returncode == 0, done.stderr
    return json.loads((out / "summary.json").read_text()), (out / "bifurcation.csv").read_text()


def test_a_dotted_key_sweeps_as_its_shorthand_and_shares_its_cache(tmp_path, monkeypatch):
    """--parameter drive.speed_rpm, the dotted key of the scene, sweeps the points that its
    shorthand speed sweeps, each run on its own (their tables equal point for point); a rerun
    by the other name in the shorthand's cache reads every point and runs none (the entries
    are keyed by the points' scenes, which are one)."""
    from pinbore.core import parallel

    named, named_table = speed_sweep("speed", tmp_path / "named", tmp_path / "named-cache")
    dotted, dotted_table = speed_sweep("drive.speed_rpm", tmp_path / "dotted", tmp_path / "dotted-cache")
    assert dotted_table == named_table and dotted["counts"] == named["counts"]
    assert (named["parameter"], dotted["parameter"]) == ("speed", "drive.speed_rpm")
    assert sorted(p.name for p in (tmp_path / "named-cache").iterdir()) == \
        sorted(p.name for p in (tmp_path / "dotted-cache").iterdir())
    stamps = {p.name: p.stat().st_mtime_ns for p in (tmp_path / "named-cache").iterdir()}

    def no_runner(*args, **kwargs):
        raise AssertionError("a point ran")
    monkeypatch.setattr(parallel, "executor", no_runner)
    _, again = speed_sweep("drive.speed_rpm", tmp_path / "again", tmp_path / "named-cache")
    assert again == named_table
    assert {p.name: p.stat().st_mtime_ns for p in (tmp_path / "named-cache").iterdir()} == stamps


@pytest.mark.parametrize("parameter, message", [
    ("drive.speed", "--parameter drive.speed: no such key in the scene (--parameter takes a dotted key"),
    ("clearance_joints.1.friction.mu", "--parameter clearance_joints.1.friction.mu: clearance_joints.1: no such "
                                       "item (the list has 1)"),
    ("clearance_joints.0.name", "--parameter clearance_joints.0.name: not a number"),
    ("clearence", "--parameter clearence: no such key in the scene"),
    ("drive..speed_rpm", "--parameter: 'drive..speed_rpm' must be a dotted key of the scene"),
])
def test_a_bad_dotted_key_is_one_line_naming_it(tmp_path, parameter, message):
    """A parameter the scene has no number at is one line naming the key, exit 2, before any
    model is built (under a second of CPU, the CLI's imports included), nothing written."""
    run = main_in_child("dynamics", FLORES, "--analysis", "bifurcation", "--parameter", parameter,
                        "--range", "1", "2", "--points", "2", "--out", tmp_path / "out")
    assert run.returncode == 2 and message in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and "Traceback" not in run.stderr
    assert float(run.stdout) < 1.0
    assert not (tmp_path / "out").exists() and not (tmp_path / "out-cache").exists()


@pytest.mark.parametrize("extra, message", [
    (["--analysis", "bifurcation", "--parameter", "clearance", "--range", "5e-4", "2e-4"], "--range: HIGH must exceed LOW"),
    (["--analysis", "bifurcation", "--parameter", "clearance", "--range", "2e-4", "5e-4", "--points", "0"], "--points: at least 2"),
    (["--analysis", "bifurcation", "--parameter", "friction", "--range", "0.1", "0.2"], "--parameter friction"),
    (["--analysis", "design", "--range", "2e-4", "5e-4"], "--speeds"),
])
def test_bad_sweeps_are_one_line_exit_2(tmp_path, extra, message):
    done = pinbore("dynamics", FLORES, *extra, "--out", tmp_path / "out")
    assert done.returncode == 2, done.stderr
    assert message in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_the_same_sweep_runs_on_a_dask_scheduler(tmp_path):
    """--scheduler ADDRESS: the points go through the cluster's executor (an in-process
    cluster here) and come back the same as from local processes."""
    distributed = pytest.importorskip("distributed")
    values = [0.20, 0.28]
    with distributed.LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        rows = duffing_sweep(values, tmp_path / "dask", scheduler=cluster.scheduler_address)
    assert [(r["kind"], r["period"]) for r in rows] == [("periodic", 1), ("periodic", 2)]


def test_the_report_checks_the_bifurcation_table_against_its_summary(tmp_path):
    """bifurcation.csv is read by the report: its points' classes (one row at least per swept
    value, a failed one included) must be those summary.json counts; another header or
    other counts are one InputError line."""
    from pinbore.core.errors import InputError
    from pinbore.reduced import report
    from pinbore.reduced.dynamics import plots

    path = tmp_path / "bifurcation.csv"
    rows = [[1e-4, "chaotic", "", 900.0, 1e-5, 2e-5], [1e-4, "chaotic", "", 900.0, 2e-5, 1e-5],
            [2e-4, "periodic", 1, "", 3e-5, 0.0], [3e-4, "failed", "", "", None, None]]
    plots.write_table(path, studies.BIFURCATION_COLUMNS, rows)
    report.check_bifurcation_table(path, {"counts": {"chaotic": 1, "failed": 1, "periodic": 1}})
    with pytest.raises(InputError, match="classes"):
        report.check_bifurcation_table(path, {"counts": {"chaotic": 2, "periodic": 1}})
    plots.write_table(path, ["value", "kind"], rows)
    with pytest.raises(InputError, match="header"):
        report.check_bifurcation_table(path, {"counts": {}})


def test_the_report_shows_a_continued_response_of_the_benchmarks(tmp_path):
    """A continued response that `make bench` keeps (bench/continuation_<scene>/) shows in
    the dynamics section beside make's own, said to come from there."""
    import json

    from pinbore.reduced import report

    summary = {"scene_file": "scenes/reduced/deployed_panel_shaken.toml", "parameter": "frequency",
               "start": 3.0, "points": 2, "converged": True, "reason": "",
               "bifurcations": [{"kind": "fold", "value": 3.18, "amplitude_m": 1e-4,
                                 "floquet_multipliers": [[1.0, 0.0], [0.5, 0.0]]}],
               "start_floquet_multipliers": [[0.5, 0.0], [0.2, 0.1]], "start_stable": True,
               "seconds_per_point": 1.5, "wall_time_s": 3.0}
    (tmp_path / "build" / "dynamics").mkdir(parents=True)
    (tmp_path / "bench" / "continuation_deployed_panel_shaken").mkdir(parents=True)
    (tmp_path / "bench" / "continuation_deployed_panel_shaken" / "summary.json").write_text(json.dumps(summary))
    page = report.dynamics_section(tmp_path / "build", tmp_path / "bench")
    assert "Response by continuation: deployed_panel_shaken" in page
    assert "computed by <code>make bench</code>" in page and "fold" in page
