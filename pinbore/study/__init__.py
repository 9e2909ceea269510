"""`pinbore study STUDY.toml --out DIR`: a scene's parameters swept or sampled, every point run,
the quantities it collects tabulated, with their statistics, Sobol indices and tolerance band.

The study file (a strict model: unknown keys are refused):

    base = "../scenes/reduced/slider_crank_flores2004.toml"   # relative to the study file
    confidence = 0.95                                          # of every interval
    [set]                          # fixed changes to the base scene (a key may be new)
    duration = 0.012
    [parameters."clearance_joints.0.journal_radius"]           # a dotted key of the scene
    distribution = { kind = "uniform", low = 9.4e-3, high = 9.6e-3 }
    [parameters."clearance_joints.0.restitution"]
    values = [0.7, 0.9]            # or grid = { start, stop, num }
    [sampling]
    method = "monte_carlo"         # grid | monte_carlo | lhs | sobol | saltelli
    points = 200                   # random plans (saltelli: N base rows, N (d + 2) runs)
    seed = 1
    [[collect]]
    name = "peak_force_N"
    path = "clearance_joints.rod_slider.peak_normal_force_N"   # into the point's result
    [[collect]]                    # or a statistic of a mechanism's time-series column
    name = "jitter_rad_per_s"
    column = "crank_omega_rad_per_s"
    statistic = "std"              # max min max_abs peak_to_peak mean rms std final
    window_s = [0.006, 0.012]      # optional (s)
    [limit]                        # optional: P(quantity > threshold), against target
    quantity = "peak_force_N"
    threshold = 2.0e4
    target = 0.05
    [surrogate]                    # optional (random plans): a polynomial chaos of this
    degree = 4                     # total degree in the parameters: its Sobol indices
    [tolerance]                    # optional: the widest band of a uniform parameter
    parameter = "clearance_joints.0.journal_radius"
    limit = { quantity = "peak_force_N", threshold = 5.0e4 }
    target = 0.01

A point runs through the stage of its base scene's `kind` (pinbore.stages: any stage that
takes a scene kind), and its result is what that stage writes: the summary of `pinbore
reduced` (summary.json, computed in process, no files; with the statistics of its collected
columns under `series`), impact.json of `pinbore impact`, modes.json of `pinbore modes`,
summary.json of `pinbore wear`, result.json of `pinbore fem` with the last row of its curve
under `curve_last`.

Every point's scene is validated before any run (a point that breaks a rule is one line
naming the point, the key and the rule; exit 2, nothing written). The points run in parallel
through the one sweep engine of the package (pinbore.core.sweep: long-lived local processes or a
Dask cluster), cached by content: the name of a point's cache file is the SHA-256 of its stage,
its whole scene, the files the scene names and the source of the code that runs it (the
modules its stage's model, runner and point function import, read by pinbore.core.codedeps,
and the class Point), so a
rerun runs only new or changed points, and a killed study resumes. A failed point is marked
in results.csv with its reason; the command then exits 1 and keeps the others.

Writes DIR/results.csv (and, from PARQUET_ROWS points, the same table as DIR/results.parquet:
typed columns that pandas, Polars, DuckDB or Dask read without parsing text),
DIR/summary.json, DIR/statistics.json, DIR/histograms.png, DIR/exceedance.png and, for a
saltelli plan, DIR/sobol.csv and DIR/sobol.png, for a
tolerance DIR/tolerance.json and DIR/tolerance.png. The statistics are those of
pinbore.core.uq, over the points whose status is "complete".

The package, by idea (each module imports only those above it):

    schema    the study file's model (Study and its tables), load, inputs
    point     one point in a worker (Point), a column's statistic, the point's code (its key)
    plan      the plan's matrix, labels and names, each point's scene and key (Plan), point_scene
    tables    results.csv and results.parquet
    stats     statistics, surrogates, the tolerance band
    figures   histograms, exceedance, Sobol indices, the tolerance band
    runner    the command: its options, the run and its outputs
    report    the report's section and answers
"""

# the package's names, as pinbore.study's callers use them (each documented in its module)
from pinbore.study.schema import SPEC_KEYS, STATISTICS, Case, Collect, Distribution, Grid  # noqa: F401
from pinbore.study.schema import LabelText, Limit, Parameter, Sampling, Study, Surrogate  # noqa: F401
from pinbore.study.schema import Threshold, Tolerance, flatten, inputs, load  # noqa: F401
from pinbore.study.point import KEPT_SUFFIXES, Point, column_statistic, point_code  # noqa: F401
from pinbore.study.plan import ABSENT, MAX_POINTS, Plan, matrix, planned_points, point_scene  # noqa: F401
from pinbore.study.plan import value_labels  # noqa: F401
from pinbore.study.tables import PARQUET_ROWS, results_header, table, write_parquet, write_results  # noqa: F401
from pinbore.study.stats import complete, sampled, statistics, surrogates, tolerance  # noqa: F401
from pinbore.study.figures import figures_of, sobol_outputs, tolerance_figure  # noqa: F401
from pinbore.study.runner import Options, command, options, run  # noqa: F401
from pinbore.study.report import CHAOS_HOLDS, answers, section  # noqa: F401
