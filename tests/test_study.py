"""`pinbore study` and the statistics under it (pinbore.core.uq): each against an independent
reference: the Ishigami function's closed-form Sobol indices, the moments of a linear model of
Gaussian inputs, scipy's exact binomial interval, a tolerance band known in closed form, and
the clearance c = R_bearing - R_journal for the runner's substitutions; the runner's cache,
resume after SIGKILL and Dask cluster against counts of the runs and an uninterrupted run."""

import csv
import json
import math
import os
import signal
import subprocess
import sys
import time
import tomllib

import numpy as np
import pytest
from conftest import ROOT, main_in_child, pinbore
from scipy import stats

from pinbore.core import uq
from pinbore.core.errors import InputError

ISHIGAMI_FIRST = np.array([0.3139, 0.4424, 0.0])     # a = 7, b = 0.1 (Ishigami & Homma 1990;
ISHIGAMI_TOTAL = np.array([0.5576, 0.4424, 0.2437])  # Saltelli et al. 2008, table 4.3)
BOUNDS = [stats.uniform(-math.pi, 2 * math.pi)] * 3


def ishigami(x, a=7.0, b=0.1):
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_indices(n, seed):
    return uq.sobol(ishigami(uq.plan("saltelli", BOUNDS, n, seed)), 3, 0.95, resamples=300, seed=seed)


def test_sobol_indices_of_the_ishigami_function_converge_to_the_closed_form():
    """At N = 1024 and 16384 base rows (3 seeds each), every 95 % bootstrap interval holds the
    closed-form index (the references are given to 4 digits: 5e-5, far inside the
    intervals' half-widths of >= 0.02). The intervals shrink as N^-1/2 (order 0.5 +- 0.05: the
    bootstrap of a mean); the errors at least as fast (observed order >= 0.4, mean of 3 seeds:
    a scrambled Sobol' plan converges faster than Monte Carlo's 0.5)."""
    errors, widths = {}, {}
    for n in (1024, 16384):
        err, width = [], []
        for seed in (1, 2, 3):
            s = ishigami_indices(n, seed)
            for est, ci, ref in ((s["first"], s["first_interval"], ISHIGAMI_FIRST),
                                 (s["total"], s["total_interval"], ISHIGAMI_TOTAL)):
                assert np.all(ci[:, 0] - 5e-5 <= ref) and np.all(ref <= ci[:, 1] + 5e-5), (n, seed, est, ci)
                err.append(np.max(np.abs(est - ref)))
                width.append(np.max(ci[:, 1] - ci[:, 0]) / 2)
        errors[n], widths[n] = np.mean(err), np.mean(width)
    assert errors[16384] < 0.005
    assert math.log(widths[1024] / widths[16384]) / math.log(16) == pytest.approx(0.5, abs=0.05)
    assert math.log(errors[1024] / errors[16384]) / math.log(16) >= 0.4


def ishigami_exact(a=7.0, b=0.1):
    """The Ishigami function's mean, variance and indices in closed form [Sudret2008]:
    V1 = (1 + b pi^4/5)^2 / 2, V2 = a^2/8, V13 = 8 b^2 pi^8 / 225."""
    v1, v2, v13 = (1 + b * math.pi**4 / 5) ** 2 / 2, a**2 / 8, 8 * b**2 * math.pi**8 / 225
    v = v1 + v2 + v13
    return a / 2, v, np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def test_a_polynomial_chaos_of_the_ishigami_function_gives_its_indices():
    """Legendre chaos fitted by least squares on a Latin hypercube: at degree 12 on 1000 points
    (455 terms) the mean, variance and the six indices equal the closed form within 1e-4 (the
    function is smooth: the truncation error falls faster than any power of the degree; 1e-5
    measured), and the leave-one-out error estimates it (< 1e-5 of the variance); at degree 6
    (84 terms) the indices are within 0.05 and the leave-one-out error says so (> 1e-3)."""
    mean, variance, first, total = ishigami_exact()
    u = uq.unit_plan("lhs", 3, 1000, 5)
    y = ishigami(-math.pi + 2 * math.pi * u)
    fit = uq.chaos(u, y, 12)
    assert fit.mean == pytest.approx(mean, abs=1e-4 * math.sqrt(variance))
    assert fit.variance == pytest.approx(variance, rel=1e-4)
    assert np.abs(fit.first - first).max() < 1e-4 and np.abs(fit.total - total).max() < 1e-4
    assert fit.loo_error < 1e-5
    coarse = uq.chaos(u, y, 6)
    assert np.abs(coarse.total - total).max() < 0.05 and coarse.loo_error > 1e-3
    with pytest.raises(ValueError, match="needs at least"):
        uq.chaos(u[:100], y[:100], 6)


def test_a_polynomial_chaos_is_exact_for_a_polynomial():
    """y = 1 + 2 z1 + 3 z1 z2 + z3^2 with z = 2u - 1 uniform on [-1, 1]: E y = 1 + 1/3,
    V = 4/3 + 9/9 + (1/5 - 1/9) = 4/3 + 1 + 4/45; S1 = (4/3)/V, S3 = (4/45)/V, S12 = 1/V:
    to round-off at degree 2 from 30 points (10 terms), leave-one-out error 0."""
    u = uq.unit_plan("monte_carlo", 3, 30, 2)
    z = 2 * u - 1
    fit = uq.chaos(u, 1 + 2 * z[:, 0] + 3 * z[:, 0] * z[:, 1] + z[:, 2] ** 2, 2)
    v = 4 / 3 + 1 + 4 / 45
    assert fit.mean == pytest.approx(4 / 3, abs=1e-12) and fit.variance == pytest.approx(v, rel=1e-12)
    assert fit.first == pytest.approx([4 / 3 / v, 0.0, 4 / 45 / v], abs=1e-12)
    assert fit.total == pytest.approx([(4 / 3 + 1) / v, 1 / v, 4 / 45 / v], abs=1e-12)
    assert fit.loo_error < 1e-20


def test_mean_and_spread_of_a_linear_model_of_gaussian_inputs():
    """y = c . x, x_i ~ N(mu_i, s_i) independent: E y = c . mu, std y = sqrt(sum c_i^2 s_i^2).
    At 99.9 % confidence the Student-t and chi-square intervals of 4000 Monte Carlo and LHS
    samples hold them (a miss has probability 1e-3 per seed); the intervals' half-widths
    match their closed forms t s / sqrt(n) and the chi-square quantiles."""
    c, mu, sd = np.array([2.0, -1.0, 0.5]), np.array([1.0, 3.0, -2.0]), np.array([0.1, 0.4, 2.0])
    dists = [uq.distribution("normal", mean=m, std=s) for m, s in zip(mu, sd)]
    mean_ref, std_ref = c @ mu, math.sqrt(np.sum((c * sd) ** 2))
    for method in ("monte_carlo", "lhs"):
        y = uq.plan(method, dists, 4000, seed=11) @ c
        mean, lo, hi = uq.mean_interval(y, 0.999)
        assert lo <= mean_ref <= hi
        assert (hi - lo) / 2 == pytest.approx(stats.t.ppf(0.9995, 3999) * np.std(y, ddof=1) / math.sqrt(4000), rel=1e-12)
        std, slo, shi = uq.std_interval(y, 0.999)
        assert slo <= std_ref <= shi
        assert slo < std < shi and shi / slo < 1.1   # sqrt(chi2 ratio) at n = 4000: 1.076
    described = uq.describe(uq.plan("monte_carlo", dists, 4000, seed=3) @ c, 0.999)
    q = stats.norm(mean_ref, std_ref).ppf([0.05, 0.5, 0.95])
    for key, ref in zip(("q05", "q50", "q95"), q):   # distribution-free order-statistic intervals
        assert described[f"{key}_interval"][0] <= ref <= described[f"{key}_interval"][1]


@pytest.mark.parametrize("n", [5, 20, 99, 1000, 4000])
@pytest.mark.parametrize("p", [0.05, 0.5, 0.95])
def test_the_quantile_and_spread_intervals_are_scipys_binomial_and_chi_square_quantiles(n, p):
    """The order statistics of the distribution-free quantile interval are scipy.stats.binom's
    quantiles (lower: ppf(alpha), upper: ppf(1 - alpha) + 1) and the spread interval's bounds
    are chi2.ppf's: the intervals are computed from scipy.special alone."""
    y = np.arange(1.0, n + 1)   # Y_(k) = k
    alpha = 0.025
    _, low, high = uq.quantile_interval(y, p, 0.95)
    lo, hi = int(stats.binom.ppf(alpha, n, p)), int(stats.binom.ppf(1 - alpha, n, p)) + 1
    assert (low if lo >= 1 else math.nan) == pytest.approx(lo if lo >= 1 else math.nan, nan_ok=True)
    assert (high if hi <= n else math.nan) == pytest.approx(hi if hi <= n else math.nan, nan_ok=True)
    for q in (1e-3, 0.025, 0.5, 0.975):
        assert uq.chi2_quantile(q, n - 1) == pytest.approx(stats.chi2.ppf(q, n - 1), rel=1e-12)


@pytest.mark.parametrize("k, n", [(0, 10), (1, 10), (7, 50), (50, 50), (3, 1000), (500, 1000)])
@pytest.mark.parametrize("confidence", [0.9, 0.95, 0.99])
def test_clopper_pearson_is_scipys_exact_binomial_interval(k, n, confidence):
    """Two-sided and one-sided upper, against scipy.stats.binomtest's exact intervals (the same
    beta quantiles: rel 1e-9)."""
    ref = stats.binomtest(k, n).proportion_ci(confidence, method="exact")
    assert uq.clopper_pearson(k, n, confidence) == pytest.approx((ref.low, ref.high), rel=1e-9, abs=1e-12)
    upper = stats.binomtest(k, n, alternative="less").proportion_ci(confidence, method="exact")
    assert uq.clopper_pearson(k, n, confidence, "upper")[1] == pytest.approx(upper.high, rel=1e-9)
    assert uq.exceedance(np.r_[np.ones(k), np.zeros(n - k)], 0.5, confidence).probability == k / n


def test_tolerance_band_of_a_known_exceedance():
    """x uniform on [-1, 1], y = |x|: inside the band |x| <= h, P(y > 0.5) = (h - 0.5) / h
    (0 for h <= 0.5), so the widest band with P <= 0.01 is h* = 0.5 / 0.99 = 0.50505. The
    95 % upper bound answer lies between 0.5 (where the bound on k = 0 of ~10 000 points is
    3e-4) and h* (it is conservative)."""
    x = np.random.default_rng(5).uniform(-1, 1, 20000)
    answer = uq.tolerance_band(x, np.abs(x), 0.0, 1.0, 0.5, 0.01, 0.95)
    assert 0.5 <= answer["half_width"] <= 0.5 / 0.99
    assert answer["upper_bound"] <= 0.01
    # the fewest independent points that can show P <= 1 % at 95 %: (1 - 0.01)^n <= 0.05
    assert answer["fewest_points_needed"] == 299


# ---- the runner, on a short slider-crank (a half revolution: tens of ms a point once compiled)

FLORES = ROOT / "scenes/reduced/slider_crank_flores2004.toml"


def study_text(journal_radii=None, distribution=None, points=None, duration=0.006, friction=False,
               extra=""):
    parameter = (f"values = {list(journal_radii)!r}" if journal_radii is not None
                 else f"distribution = {distribution}")
    sampling = (f'method = "monte_carlo"\npoints = {points}\nseed = 4' if points else 'method = "grid"')
    fric = '"clearance_joints.0.friction" = { law = "coulomb_ambrosio", mu = 0.05 }\n' if friction else ""
    return f"""base = "{FLORES}"
[set]
duration = {duration}
{fric}
[parameters."clearance_joints.0.journal_radius"]
{parameter}
[sampling]
{sampling}
[[collect]]
name = "peak_force_N"
path = "clearance_joints.rod_slider.peak_normal_force_N"
[[collect]]
name = "clearance_m"
path = "clearance_joints.rod_slider.clearance_m"
{extra}"""


COLUMN = """[[collect]]
name = "slider_lowest_x_m"
column = "slider_x_m"
statistic = "min"
window_s = [0.0, 0.0065]
"""


def rows_of(out):
    with open(out / "results.csv") as f:
        return list(csv.DictReader(f))


def quantities(rows):
    return [(r["clearance_joints.0.journal_radius"], r["peak_force_N"], r["status"]) for r in rows]


def test_a_study_reruns_only_what_changed(tmp_path):
    """Four journal radii: every point runs, and the clearance each reports is 10 mm - r (the
    substitution reached the scene); a second run runs none (the cache files untouched); one
    radius changed runs that point only."""
    study = tmp_path / "study.toml"
    radii = [9.50e-3, 9.55e-3, 9.60e-3, 9.65e-3]
    study.write_text(study_text(radii))
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    rows = rows_of(tmp_path / "out")
    assert [r["ran"] for r in rows] == ["True"] * 4
    for r, radius in zip(rows, radii):
        assert float(r["clearance_m"]) == pytest.approx(10.0e-3 - radius, rel=1e-9)
    cache = tmp_path / "out-cache"
    stamps = {p.name: p.stat().st_mtime_ns for p in cache.iterdir()}
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    assert [r["ran"] for r in rows_of(tmp_path / "out")] == ["False"] * 4
    assert quantities(rows_of(tmp_path / "out")) == quantities(rows)
    assert {p.name: p.stat().st_mtime_ns for p in cache.iterdir()} == stamps
    study.write_text(study_text([9.50e-3, 9.55e-3, 9.62e-3, 9.65e-3]))
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    assert [r["ran"] for r in rows_of(tmp_path / "out")] == ["False", "False", "True", "False"]
    assert len(list(cache.glob("*.json"))) == 5


def test_an_fe_point_is_keyed_on_every_module_its_run_loads():
    """An FE or impact point's cache key covers the code of its run: the import closure of
    its stage's model, runner and point function (study.point_code: the registry read by
    core.codedeps). Every pinbore
    module its run loads (pinbore.fem.run and pinbore.fem.impact.run imported in a fresh
    interpreter) lies in it, so no edit its result could see leaves its cached result
    standing; the multibody engine and the calibration are not, so their edits rerun no FE
    point (a mechanism's key covers them)."""
    from pinbore import study
    from pinbore.core import codedeps

    loaded = subprocess.run(
        [sys.executable, "-c", "import sys, pinbore.fem.run, pinbore.fem.impact.run; "
         "print(' '.join(m for m in sys.modules if m.startswith('pinbore.')))"],
        capture_output=True, text=True, check=True).stdout.split()
    graph = codedeps.installed_graph()
    # a compiled module's submodules are its own (pinbore.core.cpp.laws); a namespace
    # package has no code
    loaded = {codedeps.project_module(m, graph.files) for m in loaded} - {None}
    both = graph.closure(*study.point_code("fem"), *study.point_code("impact"))
    assert loaded - both == set()
    for stage in ("fem", "impact", "modes"):
        code = graph.closure(*study.point_code(stage))
        assert not any(m.startswith(("pinbore.reduced.", "pinbore.calibration")) for m in code)
    assert {"pinbore.fem.modes.file", "pinbore.laws.lawsfile", "pinbore.reduced.mechanism.model",
            "pinbore.core.cpp"} <= graph.closure(*study.point_code("reduced"))


def test_a_killed_study_resumes_without_losing_or_repeating_a_point(tmp_path):
    """SIGKILL (the whole process group: the study and its workers) once some points are
    cached; the rerun runs exactly the others, leaves the cached ones untouched, and its table
    equals that of an uninterrupted run."""
    study = tmp_path / "study.toml"
    study.write_text(study_text(distribution='{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                points=16, duration=0.024, friction=True))
    whole = pinbore("study", study, "--out", tmp_path / "whole", "--workers", "2", "--cache", tmp_path / "c1")
    assert whole.returncode == 0, whole.stderr
    cache = tmp_path / "c2"
    child = subprocess.Popen([sys.executable, "-m", "pinbore.cli", "study", study, "--out", tmp_path / "out",
                              "--workers", "2", "--cache", cache], start_new_session=True,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 300
    while len(list(cache.glob("*.json"))) < 4 and time.monotonic() < deadline and child.poll() is None:
        time.sleep(0.02)
    os.killpg(child.pid, signal.SIGKILL)
    child.wait()
    kept = {p.name: p.stat().st_mtime_ns for p in cache.glob("*.json")}
    assert 4 <= len(kept) < 16 and not (tmp_path / "out").exists()
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2", "--cache", cache)
    assert done.returncode == 0, done.stderr
    rows = rows_of(tmp_path / "out")
    assert sum(r["ran"] == "True" for r in rows) == 16 - len(kept)
    assert {p.name: p.stat().st_mtime_ns for p in cache.glob("*.json") if p.name in kept} == kept
    assert quantities(rows) == quantities(rows_of(tmp_path / "whole"))


@pytest.mark.parametrize("signum, group, code, wait", [(signal.SIGINT, True, 130, 2.5),
                                                       (signal.SIGTERM, False, 143, 0.3)],
                         ids=["Ctrl-C", "SIGTERM as the workers start"])
def test_a_stopped_study_stops_its_workers_at_once(tmp_path, signum, group, code, wait):
    """SIGTERM to the study, or Ctrl-C (SIGINT to the whole process group, its workers
    included), while its two workers run points of seconds each, or as they start: the study
    ends within two seconds in one line, its workers with it, nothing left (the workers' own
    KeyboardInterrupt had printed their tracebacks, the study waited for the points under
    way, 25 s, and a worker whose start the stop cut printed an EOFError)."""
    from conftest import stopped_midrun

    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3, 9.55e-3, 9.6e-3, 9.65e-3], duration=8.0))
    done, seconds, left, temporaries = stopped_midrun(
        ["study", study, "--out", "out", "--workers", "2"], tmp_path, tmp_path / "out", signum, wait, group)
    assert done.returncode == code and seconds < 2.0, (done.returncode, seconds, done.stderr)
    lines = [line.split("\r")[-1] for line in done.stderr.strip().split("\n")]
    assert lines[-1] == f"pinbore study: {'terminated' if code == 143 else 'interrupted'}; outputs under way removed"
    assert "Traceback" not in done.stderr and "KeyboardInterrupt" not in done.stderr
    assert left == [] and temporaries == [] and not (tmp_path / "out").exists()


def test_a_saltelli_study_finds_what_a_quantity_depends_on(tmp_path):
    """The clearance each point reports is 10 mm - journal radius, a function of the radius
    alone: its Sobol indices are exactly 0 for the restitution (the AB block that swaps the
    restitution reproduces A) and 1 for the radius (within the bootstrap interval, which must
    hold 1), 16 x 4 points through the runner."""
    study = tmp_path / "study.toml"
    study.write_text(study_text(distribution='{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }')
                     .replace('method = "grid"', 'method = "saltelli"\npoints = 16\nseed = 3')
                     + '[parameters."clearance_joints.0.restitution"]\n'
                       'distribution = { kind = "uniform", low = 0.7, high = 0.95 }\n')
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    assert len(rows_of(tmp_path / "out")) == 16 * 4
    with open(tmp_path / "out" / "sobol.csv") as f:
        sobol = {(r["quantity"], r["parameter"]): r for r in csv.DictReader(f)}
    radius = sobol[("clearance_m", "clearance_joints.0.journal_radius")]
    restitution = sobol[("clearance_m", "clearance_joints.0.restitution")]
    assert float(restitution["first"]) == 0 and float(restitution["total"]) == 0
    for order in ("first", "total"):
        assert float(radius[f"{order}_low"]) <= 1.0 <= float(radius[f"{order}_high"])


def test_a_surrogate_study_finds_what_a_quantity_depends_on(tmp_path):
    """[surrogate] on a Latin hypercube of 16 points in the journal radius and the
    restitution: the reported clearance is 10 mm - the radius, linear in it, so its chaos of
    degree 2 has the closed-form mean and spread of a uniform radius, total index 1 for the
    radius and 0 for the restitution (to round-off), and a leave-one-out error of 0."""
    study = tmp_path / "study.toml"
    study.write_text(study_text(distribution='{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }')
                     .replace('method = "grid"', 'method = "lhs"\npoints = 16\nseed = 3')
                     + '[parameters."clearance_joints.0.restitution"]\n'
                       'distribution = { kind = "uniform", low = 0.7, high = 0.95 }\n'
                       '[surrogate]\ndegree = 2\n')
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    chaos = json.loads((tmp_path / "out" / "statistics.json").read_text())["surrogate"]["clearance_m"]
    assert chaos["mean"] == pytest.approx(10e-3 - 9.525e-3, rel=1e-9)
    assert chaos["std"] == pytest.approx(0.15e-3 / math.sqrt(12), rel=1e-6)
    assert chaos["total"]["clearance_joints.0.journal_radius"] == pytest.approx(1.0, abs=1e-9)
    assert chaos["total"]["clearance_joints.0.restitution"] == pytest.approx(0.0, abs=1e-9)
    assert chaos["loo_error"] < 1e-12


@pytest.mark.slow
def test_a_dask_cluster_gives_the_table_of_local_processes(tmp_path):
    """A local Dask cluster of 2 worker processes (each compiles or loads the engine once)
    computes the same points as the local pool, to the bit."""
    distributed = pytest.importorskip("distributed")
    study = tmp_path / "study.toml"
    study.write_text(study_text([9.50e-3, 9.58e-3, 9.65e-3]))
    local = pinbore("study", study, "--out", tmp_path / "local", "--workers", "2")
    assert local.returncode == 0, local.stderr
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        done = pinbore("study", study, "--out", tmp_path / "dask", "--scheduler", cluster.scheduler_address)
    assert done.returncode == 0, done.stderr
    assert quantities(rows_of(tmp_path / "dask")) == quantities(rows_of(tmp_path / "local"))
    assert [r["ran"] for r in rows_of(tmp_path / "dask")] == ["True"] * 3


def test_a_dask_worker_killed_during_a_study_loses_no_point(tmp_path):
    """SIGKILL to one of the two workers of a local Dask cluster while it runs a point (its
    nanny starts a new one; the scheduler gives the lost worker's points to the workers left):
    the study completes, its table equals that of local processes, and every point ran once
    in this study (none from a cache, none missing)."""
    distributed = pytest.importorskip("distributed")
    study = tmp_path / "study.toml"
    study.write_text(study_text(distribution='{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                points=12, duration=0.024, friction=True))
    local = pinbore("study", study, "--out", tmp_path / "local", "--workers", "2")
    assert local.returncode == 0, local.stderr
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        pids = client.run(os.getpid)
        child = subprocess.Popen([sys.executable, "-m", "pinbore.cli", "study", study, "--out",
                                  tmp_path / "dask", "--scheduler", cluster.scheduler_address],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and child.poll() is None:
            busy = [w for w, tasks in client.processing().items() if tasks and w in pids]
            if busy:   # a worker holds a point: kill it mid-run
                killed = pids[busy[0]]
                os.kill(killed, signal.SIGKILL)
                break
            time.sleep(0.01)
        else:
            pytest.fail("no worker of the cluster took a point")
        _, err = child.communicate(timeout=600)
        assert child.returncode == 0, err
        assert killed not in client.run(os.getpid).values()   # it was gone, not only busy
    rows = rows_of(tmp_path / "dask")
    assert quantities(rows) == quantities(rows_of(tmp_path / "local"))
    assert [r["ran"] for r in rows] == ["True"] * 12


def test_a_failed_point_is_marked_and_the_others_kept(tmp_path):
    """A journal radius of 9.999 mm leaves 1 um of clearance: a point the engine stops early
    on (penetration beyond its range) or whose verdict doubts it is marked with its reason;
    exit 1; the other points' results are in the table."""
    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3, 9.99999e-3]))
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "1")
    rows = rows_of(tmp_path / "out")
    if rows[1]["status"] == "complete":
        pytest.skip("the engine completed the 10 nm clearance")
    assert done.returncode == 1 and "did not complete" in done.stderr
    assert rows[0]["status"] == "complete" and rows[1]["reason"]


@pytest.mark.parametrize("installed", [True, False], ids=["pyarrow", "without pyarrow"])
def test_a_large_table_is_also_parquet_with_the_csvs_values(tmp_path, monkeypatch, installed):
    """From PARQUET_ROWS points (lowered here to 3) the results table is also Parquet:
    pyarrow, the independent reader, gives the columns of results.csv with their types (the
    parameters and quantities float64 equal to the CSV's to the last digit, ran a bool, the
    point an int64), and each row's clearance is 10 mm - r; without pyarrow the CSV alone is
    written and the summary says why."""
    from pinbore import cli
    from pinbore.study import runner   # (the command reads PARQUET_ROWS there)

    monkeypatch.setattr(runner, "PARQUET_ROWS", 3)
    if not installed:
        monkeypatch.setitem(sys.modules, "pyarrow", None)
    study = tmp_path / "study.toml"
    radii = [9.50e-3, 9.55e-3, 9.60e-3]
    study.write_text(study_text(radii))
    assert cli.main(["study", str(study), "--out", str(tmp_path / "out"), "--workers", "1"]) == 0
    rows = rows_of(tmp_path / "out")
    summary = json.loads((tmp_path / "out/summary.json").read_text())
    if not installed:
        assert not (tmp_path / "out/results.parquet").exists()
        assert summary["parquet"] == "not written: pyarrow is not installed"
        return
    import pyarrow.parquet as pq

    table = pq.read_table(tmp_path / "out/results.parquet")
    assert table.column_names == list(rows[0]) and table.num_rows == len(rows) == 3
    assert str(table.schema.field("point").type) == "int64" and str(table.schema.field("ran").type) == "bool"
    for name in ("clearance_joints.0.journal_radius", "peak_force_N", "clearance_m", "seconds"):
        assert str(table.schema.field(name).type) == "double"
        assert table.column(name).to_pylist() == [float(r[name]) for r in rows]
    assert table.column("status").to_pylist() == [r["status"] for r in rows]
    for clearance, radius in zip(table.column("clearance_m").to_pylist(), radii):
        assert clearance == pytest.approx(10.0e-3 - radius, rel=1e-9)
    assert summary["parquet"] == "results.parquet"


# ---- bad input: one line, exit 2, nothing written, before any model is built

UNIFORM = '{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }'
TOLERANCE = ('[tolerance]\nparameter = "clearance_joints.0.journal_radius"\n'
             'limit = { quantity = "peak_force_N", threshold = 4.9e4 }\ntarget = 0.01\n')
BAD = [
    ("unknown key", lambda t: t.replace("[sampling]", "colour = 3\n[sampling]"), "colour: unknown key"),
    ("no such scene key", lambda t: t.replace("journal_radius\"]", "journal_radios\"]"),
     "clearance_joints.0.journal_radios: no such key"),
    ("low above high", lambda t: t.replace("low = 9.45e-3, high = 9.6e-3", "low = 9.6e-3, high = 9.45e-3"),
     "low must be below high"),
    ("sigma <= 0", lambda t: t.replace('{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                       '{ kind = "lognormal", median = 9.5e-3, sigma = -0.1 }'), "sigma"),
    ("std <= 0", lambda t: t.replace('{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                     '{ kind = "normal", mean = 9.5e-3, std = 0.0 }'), "std"),
    ("a point outside the scene's rules", lambda t: t.replace("high = 9.6e-3", "high = 10.2e-3"), "point "),
    ("a quantity the summary lacks", lambda t: t.replace("peak_normal_force_N", "peak_force"), "collect.0.path"),
    ("a column of no body or joint", lambda t: t + COLUMN.replace("slider_x_m", "carriage_x_m"),
     "collect.2.column"),
    ("a path and a column", lambda t: t + COLUMN.replace('statistic = "min"', 'path = "impacts"\nstatistic = "min"'),
     "not both"),
    ("a window that ends before it starts", lambda t: t + COLUMN.replace("[0.0, 0.0065]", "[0.004, 0.001]"),
     "window_s"),
    ("a column without its statistic", lambda t: t + COLUMN.replace('statistic = "min"\n', ""), "statistic"),
    ("cases in a random plan", lambda t: t + '[[cases.joint]]\nlabel = "a"\n"duration" = 0.004\n',
     "cases: go with sampling.method grid"),
    ("a surrogate of more terms than the plan can fit", lambda t: t + '[surrogate]\ndegree = 30\n',
     "surrogate.degree"),
    ("no parameter", lambda t: t.replace('[parameters."clearance_joints.0.journal_radius"]\n'
                                         'distribution = { kind = "uniform", low = 9.45e-3, high = 9.6e-3 }\n', ""),
     "parameters: give at least one"),
    ("a surrogate too rich for the points",
     lambda t: t.replace("points = 50", "points = 10") + '[surrogate]\ndegree = 5\n',
     "needs sampling.points >= 12"),
    ("a negative seed", lambda t: t.replace("seed = 4", "seed = -1"), "sampling.seed"),
    ("a window after the run", lambda t: t + COLUMN.replace("[0.0, 0.0065]", "[0.5, 0.6]"),
     "collect.2.window_s: starts at 0.5 s, after the shortest run's end"),
]


@pytest.mark.parametrize("name, edit, message", BAD, ids=[b[0] for b in BAD])
def test_a_bad_study_is_one_line_before_any_model(tmp_path, name, edit, message):
    study = tmp_path / "study.toml"
    study.write_text(edit(study_text(distribution='{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                     points=50)))
    run = main_in_child("study", study, "--out", tmp_path / "out")
    assert run.returncode == 2, run.stderr
    assert message in run.stderr and len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "out-cache").exists()


BAD_GRID = [
    ("two points of one name", lambda t: t.replace("values = [0.0095, 0.0096]",
                                                   'values = [0.0095, 0.0096]\nlabels = ["c", "c"]'),
     "share the name"),
    ("a label short", lambda t: t.replace("values = [0.0095, 0.0096]",
                                          'values = [0.0095, 0.0096]\nlabels = ["c500um"]'),
     "labels: one per value"),
    ("neither parameters nor cases",
     lambda t: t.replace('[parameters."clearance_joints.0.journal_radius"]\nvalues = [0.0095, 0.0096]\n', ""),
     "parameters: give at least one"),
    ("a case without its label", lambda t: t + '[[cases.joint]]\n"clearance_joints.0.E" = 70e9\n',
     "label"),
    ("a case that breaks the scene", lambda t: t + '[[cases.joint]]\nlabel = "a"\n"clearance_joints.0.nu" = 0.6\n',
     "point 0 (joint = a"),
]


@pytest.mark.parametrize("name, edit, message", BAD_GRID, ids=[b[0] for b in BAD_GRID])
def test_a_bad_grid_is_one_line_before_any_model(tmp_path, name, edit, message):
    study = tmp_path / "study.toml"
    study.write_text(edit(study_text([9.5e-3, 9.6e-3])))
    run = main_in_child("study", study, "--out", tmp_path / "out")
    assert run.returncode == 2, run.stderr
    assert message in run.stderr and len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert not (tmp_path / "out").exists()


# more rules of the study file, each checked where the rows above show that no model loads:
# run in this process (the CLI's main), a random plan's and a grid's
BAD_FILE = [
    ("a distribution short of its parameters",
     lambda t: t.replace(UNIFORM, '{ kind = "normal", mean = 9.5e-3 }'), "a normal distribution takes mean, std"),
    ("values and a distribution", lambda t: t.replace("distribution = ", "values = [9.5e-3]\ndistribution = "),
     "give exactly one of values, grid, distribution"),
    ("labels of a distribution", lambda t: t.replace("distribution = ", 'labels = ["a"]\ndistribution = '),
     "labels name the values of a list or a grid"),
    ("a statistic of a path", lambda t: t + '[[collect]]\nname = "n"\npath = "impacts"\nstatistic = "max"\n',
     "statistic and window_s go with a column"),
    ("no points for a random plan", lambda t: t.replace("points = 50\n", ""),
     "sampling.points: monte_carlo needs the number of points"),
    ("a quantity collected twice", lambda t: t + '[[collect]]\nname = "peak_force_N"\npath = "impacts"\n',
     "collect: two quantities have one name"),
    ("a limit on a quantity not collected",
     lambda t: t + '[limit]\nquantity = "x"\nthreshold = 1.0\ntarget = 0.1\n', "limit.quantity: 'x' is not collected"),
    ("a tolerance band of a parameter not uniform",
     lambda t: t.replace(UNIFORM, '{ kind = "normal", mean = 9.5e-3, std = 1e-5 }') + TOLERANCE,
     "tolerance.parameter: 'clearance_joints.0.journal_radius' must be a parameter with a uniform"),
    ("a tolerance band of a Latin hypercube", lambda t: t.replace('"monte_carlo"', '"lhs"') + TOLERANCE,
     "tolerance: needs sampling.method monte_carlo"),
    ("a [set] key under a number", lambda t: t.replace("[set]\n", '[set]\n"duration.s" = 1.0\n'),
     "set.duration.s: duration: holds a value, not a table"),
    ("a parameter that is no number", lambda t: t.replace('"clearance_joints.0.journal_radius"]', '"clearance_joints.0.name"]'),
     "parameters.clearance_joints.0.name: clearance_joints.0.name: not a number in the base scene"),
    ("a parameter beyond a list", lambda t: t.replace('"clearance_joints.0.journal_radius"]', '"clearance_joints.3.E"]'),
     "clearance_joints.3: no such item (the list has 1)"),
]
BAD_GRID_FILE = [
    ("points of a grid", lambda t: t.replace('method = "grid"', 'method = "grid"\npoints = 5'),
     "sampling.points: a grid runs every combination"),
    ("a grid of a distribution", lambda t: t.replace("values = [0.0095, 0.0096]", f"distribution = {UNIFORM}"),
     "sampling.method: grid takes values or a grid"),
    ("a random plan of values", lambda t: t.replace('method = "grid"', 'method = "lhs"\npoints = 4'),
     "sampling.method: lhs samples distributions"),
    ("a group of no case", lambda t: t + "[cases]\njoint = []\n", "cases.joint: give at least one case"),
    ("two cases of one label", lambda t: t + '[[cases.joint]]\nlabel = "a"\nduration = 0.004\n'
                                            '[[cases.joint]]\nlabel = "a"\nduration = 0.005\n',
     "cases.joint: two cases have one label"),
    ("a chaos of a grid", lambda t: t + "[surrogate]\ndegree = 1\n", "surrogate: fits the points of a random plan"),
]


@pytest.mark.parametrize("name, edit, message, grid", [(*b, False) for b in BAD_FILE] + [(*b, True) for b in BAD_GRID_FILE],
                         ids=[b[0] for b in BAD_FILE + BAD_GRID_FILE])
def test_a_bad_study_file_is_one_line(tmp_path, name, edit, message, grid):
    study = tmp_path / "study.toml"
    study.write_text(edit(study_text([9.5e-3, 9.6e-3]) if grid else
                          study_text(distribution=UNIFORM, points=50)))
    run = pinbore("study", study, "--out", tmp_path / "out")
    assert run.returncode == 2, run.stderr
    assert message in run.stderr and len(run.stderr.strip().splitlines()) == 1, run.stderr
    assert not (tmp_path / "out").exists() and not (tmp_path / "out-cache").exists()


def test_an_unreachable_scheduler_is_one_line_and_writes_nothing(tmp_path):
    pytest.importorskip("distributed")
    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3]))
    done = pinbore("study", study, "--out", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:9")
    assert done.returncode == 2, done.stderr
    assert "--scheduler" in done.stderr and len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists() and not (tmp_path / "out-cache").exists()


@pytest.mark.parametrize("path", sorted([*(ROOT / "studies").glob("*.toml"),
                                         *(ROOT / "studies" / "convergence").glob("*.toml")]),
                         ids=lambda p: p.stem)
def test_the_shipped_studies_validate(path):
    """Every point of each shipped study is a valid scene, each its own cache key, and every
    sampled value inside its distribution's support."""
    from pinbore import study

    loaded = study.load(path)
    plan = study.Plan(path, loaded)
    method, specs = loaded.sampling.method, list(loaded.parameters.values())
    if method == "grid":
        points = math.prod(len(s.values) for s in specs) * math.prod(map(len, loaded.cases.values()))
    else:
        points = loaded.sampling.points * (len(specs) + 2 if method == "saltelli" else 1)
    assert len(plan.scenes) == points and len(set(plan.keys)) == points
    assert len(set(plan.point_names)) == points
    for j, spec in enumerate(specs):
        d = spec.distribution
        if d is not None and d.low is not None:
            assert d.low <= plan.values[:, j].min() and plan.values[:, j].max() <= d.high


def test_cases_cross_the_values_and_name_the_points():
    """Two cases of a group (each setting two keys) crossed with two labelled values: four
    points, the cases outermost, each scene holding its case's and its value's settings, each
    named prefix_case_value."""
    from pinbore import study

    path = ROOT / "studies" / "x.toml"
    text = study_text([9.5e-3, 9.6e-3]).replace(
        "values = [0.0095, 0.0096]", 'values = [0.0095, 0.0096]\nlabels = ["c500um", "c400um"]')
    text = 'name_prefix = "flores"\n' + text + (
        '[[cases.joint]]\nlabel = "soft"\n"clearance_joints.0.E" = 70e9\n"clearance_joints.0.nu" = 0.33\n'
        '[[cases.joint]]\nlabel = "steel"\n"clearance_joints.0.E" = 207e9\n"clearance_joints.0.nu" = 0.3\n')
    plan = study.Plan(path, study.Study.model_validate(tomllib.loads(text)))
    assert plan.point_names == ["flores_soft_c500um", "flores_soft_c400um",
                                "flores_steel_c500um", "flores_steel_c400um"]
    joints = [s["clearance_joints"][0] for s in plan.scenes]
    assert [(j["E"], j["nu"], j["journal_radius"]) for j in joints] == [
        (70e9, 0.33, 9.5e-3), (70e9, 0.33, 9.6e-3), (207e9, 0.3, 9.5e-3), (207e9, 0.3, 9.6e-3)]
    assert plan.cases == [{"joint": "soft"}] * 2 + [{"joint": "steel"}] * 2
    # the cases alone (no parameter): a point per case, the base's value kept
    alone = text[:text.index('[parameters.')] + text[text.index("[sampling]"):]
    plan = study.Plan(path, study.Study.model_validate(tomllib.loads(alone)))
    assert plan.point_names == ["flores_soft", "flores_steel"] and plan.values.shape == (2, 0)
    assert [s["clearance_joints"][0]["E"] for s in plan.scenes] == [70e9, 207e9]


def test_a_statistic_of_a_column_against_the_closed_form():
    """x(t) = B + A sin(w t) on unevenly spaced steps over 3 whole periods: the time-weighted
    mean B, rms sqrt(B^2 + A^2/2) and std A/sqrt(2) (trapezoidal weights: error O(h^2), here
    below 1e-5 of A at 2000 steps of a period/600 on average), and the step values' max, min,
    max_abs, peak_to_peak and final (within the sampling of a crest, (w h)^2 / 8 of A); a
    window takes only its steps, fewer than two give NaN."""
    from pinbore.study import column_statistic

    a, b, w = 2.0, 0.5, 2 * np.pi * 5.0
    rng = np.random.default_rng(1)
    steps = rng.uniform(0.5, 1.5, 1800)
    t = np.concatenate([[0.0], np.cumsum(steps)]) * (0.6 / np.sum(steps))   # 3 periods of 0.2 s
    x = b + a * np.sin(w * t)
    tol = (w * 1.5 * 0.6 / 1800) ** 2 / 8 * a
    assert column_statistic(t, x, "mean") == pytest.approx(b, abs=1e-5 * a)
    assert column_statistic(t, x, "rms") == pytest.approx(np.sqrt(b**2 + a**2 / 2), abs=1e-5 * a)
    assert column_statistic(t, x, "std") == pytest.approx(a / np.sqrt(2), abs=1e-5 * a)
    assert column_statistic(t, x, "max") == pytest.approx(b + a, abs=tol)
    assert column_statistic(t, x, "min") == pytest.approx(b - a, abs=tol)
    assert column_statistic(t, x, "max_abs") == pytest.approx(b + a, abs=tol)
    assert column_statistic(t, x, "peak_to_peak") == pytest.approx(2 * a, abs=2 * tol)
    assert column_statistic(t, x, "final") == x[-1]
    # the first half period alone: sin >= 0 there, the mean is B + 2A/pi
    assert column_statistic(t, x, "mean", [0.0, 0.1]) == pytest.approx(b + 2 * a / np.pi, abs=1e-3 * a)
    assert np.isnan(column_statistic(t, x, "mean", [0.7, 0.8]))


def test_a_column_of_the_time_series_is_collected(tmp_path):
    """A statistic of a column of the mechanism's time series: over half a crank revolution
    from the slider's outer dead centre (5000 rpm: 6 ms; the window to 6.5 ms), the slider's
    lowest x is the inner dead centre, l - r = 0.12 - 0.05 = 0.07 m, moved by at most the
    rod-slider joint's eccentricity: its radial clearance (the journal radius: 0.5 or 0.4 mm)
    plus the contact's penetration, at most the run's peak penetration (Hertz's law at 40 kN:
    about 70 um)."""
    study = tmp_path / "study.toml"
    penetration = ('[[collect]]\nname = "penetration_m"\n'
                   'path = "clearance_joints.rod_slider.peak_penetration_m"\n')
    study.write_text(study_text([9.5e-3, 9.6e-3], duration=0.0065) + COLUMN + penetration)
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "1")
    assert done.returncode == 0, done.stderr
    for row in rows_of(tmp_path / "out"):
        clearance = 10e-3 - float(row["clearance_joints.0.journal_radius"])
        assert 0 < float(row["penetration_m"]) < clearance
        assert abs(float(row["slider_lowest_x_m"]) - 0.07) <= clearance + float(row["penetration_m"])


@pytest.mark.slow
def test_an_fe_study_scales_with_the_elastic_moduli(tmp_path):
    """An FE scene's points (kind "fem": pinbore fem on each point's scene, its curve's last
    row collected): at a fixed approach, frictionless small-strain contact is linear in the
    moduli when both scale together, so E_pin = E_bore = 210 GPa gives 3 times the force per
    length of 70 GPa (rel 1e-6: the same mesh and contact set; the solver's tolerance)."""
    import tomli_w
    from conftest import scene_dict

    base = tmp_path / "base.toml"
    base.write_text(tomli_w.dumps(scene_dict(load={"steps": 2})))
    study = tmp_path / "study.toml"
    study.write_text('base = "base.toml"\n'
                     '[[cases.moduli]]\nlabel = "soft"\n"materials.pin.E" = 70e9\n"materials.bore.E" = 70e9\n'
                     '[[cases.moduli]]\nlabel = "stiff"\n"materials.pin.E" = 210e9\n"materials.bore.E" = 210e9\n'
                     '[parameters."contact.friction"]\nvalues = [0.0]\n'
                     '[[collect]]\nname = "force"\npath = "curve_last.force_per_length_N_per_m"\n')
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    force = {r["moduli"]: float(r["force"]) for r in rows_of(tmp_path / "out")}
    assert force["stiff"] == pytest.approx(3 * force["soft"], rel=1e-6)
    # each point's files are kept under its name, as pinbore fem wrote them
    for name in ("soft", "stiff"):
        last = (tmp_path / "out" / "points" / name / "curve.csv").read_text().splitlines()
        header = last[0].split(",")
        assert float(last[-1].split(",")[header.index("force_per_length_N_per_m")]) == force[name]
        assert (tmp_path / "out" / "points" / name / "result.json").exists()


@pytest.mark.mpi
@pytest.mark.slow   # 23 s: the ranks' FE itself is test_mpi's; this is the study's plumbing of --ranks
def test_an_fe_study_on_two_ranks_a_point_gives_the_curves_of_one(tmp_path):
    """`--ranks 2`: each FE point runs as `mpiexec -n 2 pinbore fem`; every curve equals that
    of one process to 1e-8 of each column's largest value (the bound of tests/test_mpi.py:
    the linear solves may take the two runs along different paths to the same Newton
    tolerance). A study of other points refuses ranks in one line."""
    import tomli_w
    from conftest import scene_dict

    from pinbore.fem import curve as fe_curve

    base = tmp_path / "base.toml"
    base.write_text(tomli_w.dumps(scene_dict(load={"steps": 3})))
    study = tmp_path / "study.toml"
    study.write_text('base = "base.toml"\n[parameters."contact.friction"]\nvalues = [0.0, 0.2]\n'
                     'labels = ["mu0", "mu02"]\n'
                     '[[collect]]\nname = "force"\npath = "curve_last.force_per_length_N_per_m"\n')
    for ranks in (1, 2):
        done = pinbore("study", study, "--out", tmp_path / f"r{ranks}", "--workers", "1",
                       "--ranks", str(ranks), "--cache", tmp_path / f"c{ranks}")
        assert done.returncode == 0, done.stderr
    for name in ("mu0", "mu02"):
        one, two = (fe_curve.read(tmp_path / f"r{ranks}" / "points" / name / "curve.csv")
                    for ranks in (1, 2))
        for a, b in ((one.force, two.force), (one.half_angle, two.half_angle)):
            assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max()
    mechanism = tmp_path / "mechanism.toml"
    mechanism.write_text(study_text([9.5e-3]))
    run = main_in_child("study", mechanism, "--out", tmp_path / "m", "--ranks", "2")
    assert run.returncode == 2 and "--ranks" in run.stderr and len(run.stderr.strip().splitlines()) == 1


@pytest.mark.slow
def test_an_impact_study_is_the_impact_command_at_each_point(tmp_path):
    """An impact scene's points (kind "impact"): each point's restitution, peak force and pin
    mass are those of `pinbore impact` on a scene file written with that density (the
    command itself, another path to the same solve: to 1e-9), and differ between the
    densities (the substitution reached the model)."""
    import tomllib

    import tomli_w

    scene = ROOT / "scenes/impact/steel_c10um_v1.toml"
    study = tmp_path / "study.toml"
    study.write_text(f'base = "{scene}"\n[parameters."materials.pin.density"]\nvalues = [7850.0, 2700.0]\n'
                     '[[collect]]\nname = "restitution"\npath = "restitution"\n'
                     '[[collect]]\nname = "peak_force"\npath = "peak_force_N_per_m"\n'
                     '[[collect]]\nname = "pin_mass"\npath = "pin_mass_kg_per_m"\n')
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    rows = rows_of(tmp_path / "out")
    assert float(rows[1]["pin_mass"]) < 0.5 * float(rows[0]["pin_mass"])
    for row in rows:
        data = tomllib.loads(scene.read_text())
        data["materials"]["pin"]["density"] = float(row["materials.pin.density"])
        direct = tmp_path / f"direct_{row['point']}.toml"
        direct.write_text(tomli_w.dumps(data))
        run = pinbore("impact", direct, "--out", tmp_path / f"direct_{row['point']}")
        assert run.returncode == 0, run.stderr
        reference = json.loads((tmp_path / f"direct_{row['point']}" / "impact.json").read_text())
        for name, key in (("restitution", "restitution"), ("peak_force", "peak_force_N_per_m"),
                          ("pin_mass", "pin_mass_kg_per_m")):
            assert float(row[name]) == pytest.approx(reference[key], rel=1e-9)


def test_a_study_never_replaces_a_file_its_points_read(tmp_path):
    """A study whose [set] names a laws file, run with --out that file's folder (a pinbore
    output, which --out may otherwise replace): refused in one line before any point runs,
    the laws file kept (every file a point names is declared to the output guard)."""
    laws = tmp_path / "calibration"
    laws.mkdir()
    (laws / "laws.json").write_text("{}")
    (laws / ".pinbore-output").touch()
    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3]).replace("[set]\n", f'[set]\nlaws_file = "{laws / "laws.json"}"\n'))
    done = pinbore("study", study, "--out", laws)
    assert done.returncode == 2 and "holds the input" in done.stderr, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert (laws / "laws.json").read_text() == "{}" and not (tmp_path / "calibration-cache").exists()


def test_a_second_study_into_a_locked_out_is_refused_before_its_points_run(tmp_path):
    """While another run holds --out's lock, a study is refused at once (exit 2, one line),
    having run no point: the lock is taken before the work, not when the results are
    written."""
    from pinbore.core import output

    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3]))
    with output._lock(tmp_path / "out"):
        done = pinbore("study", study, "--out", tmp_path / "out")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert not (tmp_path / "out-cache").exists()


BAD_OPTIONS = [
    ("an address that is none", lambda t: ["--scheduler", "not an address"], "must be a scheduler's address"),
    ("a cache inside a file", lambda t: ["--cache", t / "study.toml" / "cache"], "which is a file"),
    ("a cache among other files", lambda t: ["--cache", ROOT / "scenes" / "reduced"], "not a cache entry"),
    ("more workers than the cores can run", lambda t: ["--workers", "10000"], "--workers"),
    ("MPI ranks of mechanism points", lambda t: ["--ranks", "2"], "--ranks: MPI ranks run FE points"),
]


@pytest.mark.parametrize("name, options, message", BAD_OPTIONS, ids=[b[0] for b in BAD_OPTIONS])
def test_bad_study_options_are_one_line_writing_nothing(tmp_path, name, options, message):
    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3]))
    before = sorted((ROOT / "scenes" / "reduced").iterdir())
    run = main_in_child("study", study, "--out", tmp_path / "out", *options(tmp_path))
    assert run.returncode == 2 and message in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists() and sorted((ROOT / "scenes" / "reduced").iterdir()) == before


EDITS = {"edited": lambda e: e | {"result": e["result"] | {"status": "complete", "seconds": -1.0}},
         "empty": lambda e: {}, "null": lambda e: None, "unsealed": lambda e: e["result"]}


def test_a_cache_entry_that_is_not_what_was_written_is_computed_again(tmp_path):
    """A cache entry carries the checksum of its result: one edited by hand (a value
    changed), emptied, null, or without its seal is computed again, never served, and the
    table is the one of a fresh run."""
    study = tmp_path / "study.toml"
    study.write_text(study_text([9.5e-3]))
    assert pinbore("study", study, "--out", tmp_path / "out").returncode == 0
    fresh = rows_of(tmp_path / "out")
    (entry,) = (tmp_path / "out-cache").glob("*.json")
    written = json.loads(entry.read_text())
    for name, edit in EDITS.items():
        entry.write_text(json.dumps(edit(written)))
        assert pinbore("study", study, "--out", tmp_path / "out").returncode == 0, name
        again = rows_of(tmp_path / "out")
        assert again[0]["ran"] in ("True", "1", "true"), name
        assert again[0]["peak_force_N"] == fresh[0]["peak_force_N"], name


@pytest.mark.parametrize("edit", [lambda t: t.replace("points = 50", "points = 10000000"),
                                  lambda t: t.replace('distribution = { kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                                      "grid = { start = 9.45e-3, stop = 9.6e-3, num = 1000000 }")
                                  .replace('method = "monte_carlo"\npoints = 50\nseed = 4', 'method = "grid"')],
                         ids=["1e7 drawn", "1e6 on a grid"])
def test_a_plan_too_large_is_refused_before_it_is_built(tmp_path, edit):
    """A plan of more than MAX_POINTS points (each a scene in memory: 1e7 had run out of
    memory after 258 s) is one line naming --force, in well under a second of CPU."""
    study = tmp_path / "study.toml"
    study.write_text(edit(study_text(distribution='{ kind = "uniform", low = 9.45e-3, high = 9.6e-3 }',
                                     points=50)))
    run = main_in_child("study", study, "--out", tmp_path / "out")
    assert run.returncode == 2 and "--force" in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1 and float(run.stdout) < 1.0


def test_a_study_varies_an_integer_key(tmp_path):
    """A count such as a sliced journal's slices is varied as the integer it is (its values
    had been put as floats, which the strict scene refused)."""
    from pinbore import study as runner

    path = tmp_path / "study.toml"
    path.write_text(f'base = "{ROOT / "scenes/reduced/deployed_panel_shaken_3d.toml"}"\n'
                    '[parameters."clearance_joints.0.slices"]\nvalues = [4, 8]\n'
                    '[sampling]\nmethod = "grid"\n'
                    '[[collect]]\nname = "impacts"\npath = "impacts"\n')
    plan = runner.Plan(path, runner.load(path))
    assert [p["clearance_joints"][0]["slices"] for p in plan.scenes] == [4, 8]
    assert all(type(p["clearance_joints"][0]["slices"]) is int for p in plan.scenes)


def test_a_points_cache_key_reads_the_source_of_every_module_of_its_run():
    """The code an FE point's key hashes: the source of every module of its closure as the
    running pinbore finds it (an editable install gives pinbore.core two folders: its
    source, and the installed tree of the compiled module, which holds no .py), the compiled
    core's binary, and of the registry (pinbore.stages) the definitions that run a point
    alone, not its table (the class Point is hashed beside it)."""
    from pinbore.core.codedeps import hashed
    from pinbore.study import point_code

    read = dict(hashed(*point_code("fem")))
    for name in ("pinbore.fem.run", "pinbore.fem.elasticity", "pinbore.meshes.model", "pinbore.laws.relief"):
        path = ROOT / name.split(".")[1] / (name.split(".", 2)[2].replace(".", "/") + ".py")
        assert read[name] == path.read_bytes()
    assert read["pinbore.core.cpp"][:4] == b"\x7fELF" or len(read["pinbore.core.cpp"]) > 10000
    assert b"def fem_point(data, point):" in read["pinbore.stages"]
    assert b"STAGES = (" not in read["pinbore.stages"]
    # nor the study's package: its plan, statistics, figures and report rerun no point
    assert not [name for name in read if name == "pinbore.study" or name.startswith("pinbore.study.")]


def test_the_report_marks_a_statistic_that_is_not_finite(tmp_path):
    """A study's statistic that is not a finite number (a one-point interval, or a
    statistics.json changed by hand) is shown as 'not finite' with a note naming the
    quantity, never as a number ('nan' had been printed as a result)."""
    from pinbore import study as runner

    folder = tmp_path / "study" / "s"
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps({"complete": 2, "points": 2, "base": "b.toml"}))
    good = {"mean": 1.0, "mean_interval": [0.9, 1.1], "std": 0.1, "q05": 0.8, "q50": 1.0,
            "q95": 1.2, "q95_interval": [1.1, 1.3]}
    (folder / "statistics.json").write_text(json.dumps(
        {"method": "monte_carlo", "confidence": 0.95,
         "quantities": {"peak_force_N": good | {"mean": float("nan")}, "clearance_m": good}}))
    page = runner.section(tmp_path, tmp_path)
    assert "nan" not in page.lower().replace("not finite", "")
    assert "not finite" in page and "so not shown as results: peak_force_N" in page
    assert "clearance_m" not in page.split("so not shown as results:")[1]


def test_a_key_the_base_leaves_out_is_set_then_varied(tmp_path):
    """A flexible body's modes, which its scene leaves at its default (every mode of its
    file), cannot be varied as it is (one line naming [set]); given a value under [set], it
    is varied as the integer it is."""
    from pinbore import study as runner

    path = tmp_path / "study.toml"
    text = (f'base = "{ROOT / "scenes/reduced/slider_crank_flores2004_flexible.toml"}"\n'
            '[parameters."bodies.1.modes"]\nvalues = [2, 4]\n'
            '[sampling]\nmethod = "grid"\n[[collect]]\nname = "impacts"\npath = "impacts"\n')
    path.write_text(text)
    with pytest.raises(InputError, match=r"parameters.bodies.1.modes: .*no such key .*under \[set\] first"):
        runner.Plan(path, runner.load(path))
    path.write_text(text.replace("[parameters.", '[set]\n"bodies.1.modes" = 6\n[parameters.'))
    plan = runner.Plan(path, runner.load(path))
    assert [p["bodies"][1]["modes"] for p in plan.scenes] == [2, 4]
    assert all(type(p["bodies"][1]["modes"]) is int for p in plan.scenes)



# the flexible pendulum's steel strip, bending in its plane (plane stress), shortened to 0.5 m
# on a coarse mesh (5 mm quadratic cells: two or three through its depth), two modes
BEAM = ROOT / "scenes/modes/pendulum_beam_2d.toml"
BEAM_SET = {"body.length": 0.5, "body.width": 0.01, "body.cell_size": 0.005,
            "reduction.fixed_interface_modes": 4, "reduction.modes": 2, "reduction.full_modes": 0}


def test_a_modes_study_gives_the_beams_bending_frequencies(tmp_path):
    """A study of a modes scene (its points run `pinbore modes`): the strip's depth w varied,
    its first two free-free bending frequencies collected. Euler-Bernoulli: f_n =
    (beta_n L)^2 / (2 pi L^2) sqrt(E I / (rho A)), I / A = w^2 / 12, so f_1 grows as w and f_2 /
    f_1 = (7.8532 / 4.7300)^2 = 2.757 whatever w (L / w >= 30: shear and rotary inertia
    below 0.5 %)."""
    study = tmp_path / "study.toml"
    study.write_text(f'base = "{BEAM}"\n[set]\n' + "".join(f'"{k}" = {v}\n' for k, v in BEAM_SET.items())
                     + '[parameters."body.width"]\nvalues = [0.010, 0.016]\n[sampling]\nmethod = "grid"\n'
                     '[[collect]]\nname = "f1_Hz"\npath = "frequencies_Hz.0"\n'
                     '[[collect]]\nname = "f2_Hz"\npath = "frequencies_Hz.1"\n')
    done = pinbore("study", study, "--out", tmp_path / "out", "--workers", "2")
    assert done.returncode == 0, done.stderr
    rows = rows_of(tmp_path / "out")
    material, L = tomllib.loads(BEAM.read_text())["material"], BEAM_SET["body.length"]
    E, rho = material["E"], material["density"]
    for row in rows:
        w = float(row["body.width"])
        f1 = 4.730041**2 / (2 * math.pi * L**2) * math.sqrt(E * w**2 / 12 / rho)
        assert float(row["f1_Hz"]) == pytest.approx(f1, rel=0.01)
        assert float(row["f2_Hz"]) / float(row["f1_Hz"]) == pytest.approx((7.853205 / 4.730041) ** 2, rel=0.01)
        assert (tmp_path / "out" / "points" / row["name"] / "modes.json").is_file()
    ratio = float(rows[1]["f1_Hz"]) / float(rows[0]["f1_Hz"])
    assert ratio == pytest.approx(0.016 / 0.010, rel=0.005)   # f_1 as w^1
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["stage"] == "modes"
