"""The report's section on the reduced (multibody) models."""

import base64
import html
import io
from pathlib import Path

from pinbore.core.errors import InputError
from pinbore.core.html import figure, note, outcome_counts, png_data, table
from pinbore.core.scene import load_json
from pinbore.reduced.mechanism import kinds, summary


def answers(build_dir: Path) -> list[tuple[str, str]]:
    """The report's first screen: for each mechanism run on a calibrated law beside its twin
    on the published law (scenes X_calibrated and X), the peak contact force of both; the
    continued response's bifurcations."""
    out = []
    runs = {path.parent.name: path for path in sorted((build_dir / "reduced").glob("*/summary.json"))}
    for name, path in runs.items():
        twin = name.removesuffix("_calibrated")
        if twin == name or twin not in runs:
            continue
        calibrated, published = summary.read(path), summary.read(runs[twin])
        change = calibrated.peak_normal_force_N / published.peak_normal_force_N - 1
        out.append((f"Peak joint force, {html.escape(twin)}",
                    f"{calibrated.peak_normal_force_N / 1e3:.3g} kN on the calibrated law, "
                    f"{published.peak_normal_force_N / 1e3:.3g} kN on the published one "
                    f"({change:+.0%}); {calibrated.impacts} impacts"))
    for path in sorted((build_dir / "dynamics").glob("continuation*/summary.json")):
        s = load_json(path, "dynamics")
        kinds_found = {}
        for b in s.get("bifurcations", []):
            kinds_found.setdefault(b["kind"].replace("_", " "), []).append(f"{b['value']:.4g}")
        unit = {"frequency": " Hz", "speed": " rpm", "clearance": " m"}.get(s["parameter"], "")
        out.append((f"Periodic response, {html.escape(Path(s['scene_file']).stem)}",
                    f"{s['points']} orbits over {html.escape(s['parameter'])}; "
                    + ("; ".join(f"{k} at {', '.join(v)}{unit}" for k, v in kinds_found.items())
                       or "no bifurcation")))
    return out


def section(build_dir: Path, bench_dir: Path) -> str:
    runs = sorted((build_dir / "reduced").glob("*/summary.json"))
    parts = ["<h2>Mechanisms with clearance joints (reduced model)</h2>",
             "<p>One engine for planar and spatial mechanisms: rigid bodies, ideal joints as "
             "constraints with Lagrange multipliers (Baumgarte stabilisation), clearance joints "
             "whose contacts carry a normal law (elastic part from the law library or calibrated "
             "on the FE study, Hunt-Crossley-type damping) and friction, or rigid impacts (Newton "
             "or Poisson restitution, then held contact); adaptive Dormand-Prince 5(4), in the "
             "compiled core (C++), that lands every contact onset on a step boundary (a stiff "
             "Rosenbrock 2(3) is the alternative).</p>"]
    if not runs:
        return "".join(parts + [note("No runs under build/reduced: run <code>make reduced</code>.")]
                       + stress_part(bench_dir))
    summaries = {path.parent: summary.read(path) for path in runs}
    rows = [[folder.name, s.status, s.impacts, f"{s.peak_normal_force_N:.4g}", s.steps,
             s.rhs_evaluations, f"{s.wall_time_s:.3f}",
             f"{s.energy_balance.relative_to_peak_kinetic:.1e}", f"{s.constraint_drift_max:.1e}"]
            for folder, s in summaries.items()]
    parts.append(table(["scene", "status", "impacts", "peak contact force (N)", "steps",
                        "RHS evaluations", "integration wall time (s)",
                        "energy residual / peak kinetic", "constraint drift (m)"], rows))
    for folder, s in summaries.items():
        if s.verdict:
            parts.append(f"<p class='note'><b>{html.escape(folder.name)} is suspect</b>: "
                         f"{html.escape('; '.join(s.verdict))}.</p>")
    for kind in kinds.KINDS.values():
        mine = [folder.name for folder, s in summaries.items() if s.model == kind.name]
        if mine:
            parts.append(f"<p>{kind.name.capitalize()} scenes ({html.escape(', '.join(mine))}): "
                         f"{kind.description}.</p>")
    for folder, s in summaries.items():
        if (folder / "acceleration.png").exists() and s.clearance_joints:
            parts.append(figure(png_data(folder / "acceleration.png"),
                                f"Scene {folder.name}: slider acceleration against crank angle, "
                                "with the ideal joint (dashed)."))
        if (folder / "attitude.png").exists():
            parts.append(figure(png_data(folder / "attitude.png"),
                                f"Scene {folder.name}: angular velocity of the first body (a "
                                "free-floating bus's attitude rates; an unactuated crank's speed), "
                                "with the ideal joints (dashed)."))
        parts += joint_figures(folder, s, kinds.KINDS[s.model].joint_caption)
        if (folder / "points.png").exists():
            parts.append(figure(png_data(folder / "points.png"),
                                f"Scene {folder.name}: the output points' elastic displacement "
                                "in their flexible bodies' floating frames."))
    parts += flexible_part(build_dir, summaries)
    parts += stress_part(bench_dir)
    return "".join(parts)


FLEXIBLE = "_flexible"   # a scene X_flexible is scene X with flexible bodies


def flexible_part(build_dir: Path, summaries: dict) -> list[str]:
    """Rigid against flexible: each run X_flexible beside X, their peak contact forces and run
    times, and a figure of the contact forces and the first body's angular velocity."""
    pairs = [(folder.parent / folder.name.removesuffix(FLEXIBLE), folder) for folder in summaries
             if folder.name.endswith(FLEXIBLE) and folder.parent / folder.name.removesuffix(FLEXIBLE) in summaries]
    if not pairs:
        return []
    parts = ["<h3>Rigid against flexible bodies</h3>",
             "<p>The same mechanism with its rigid bodies and with flexible ones (their FE modes "
             "in a floating frame, <code>pinbore modes</code>): the contact forces and the "
             "motions they disturb side by side.</p>"]
    rows = [[flexible.name, f"{summaries[rigid].peak_normal_force_N:.4g}",
             f"{summaries[flexible].peak_normal_force_N:.4g}", summaries[rigid].steps,
             summaries[flexible].steps, f"{summaries[rigid].wall_time_s:.3f}",
             f"{summaries[flexible].wall_time_s:.3f}"] for rigid, flexible in pairs]
    parts.append(table(["scene", "peak contact force, rigid (N)", "flexible (N)", "steps, rigid",
                        "flexible", "wall time, rigid (s)", "flexible (s)"], rows))
    for rigid, flexible in pairs:
        try:
            png = comparison_figure(rigid, flexible)
        except (OSError, ValueError, KeyError) as error:
            parts.append(note(f"{flexible.name}: no comparison ({error})"))
            continue
        parts.append(figure(png, f"Scene {flexible.name} (flexible) against {rigid.name} (rigid): "
                                 "contact forces and the first body's angular velocity."))
    return parts


def comparison_figure(rigid: Path, flexible: Path) -> str:
    """The PNG (data URL) of the contact forces and the first body's angular velocity of two
    runs' time series."""
    import matplotlib   # noqa: PLC0415 (the report loads matplotlib only when it draws)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt   # noqa: PLC0415
    import numpy as np   # noqa: PLC0415

    from pinbore.core.figures import save_png   # noqa: PLC0415

    runs = {name: np.genfromtxt(folder / "timeseries.csv", delimiter=",", names=True)
            for name, folder in (("rigid", rigid), ("flexible", flexible))}
    names = runs["rigid"].dtype.names
    forces = [k for k in names if k.endswith("_normal_force_N") and "_corner" not in k]
    first = next(k for k in names if k.endswith("_x_m")).removesuffix("_x_m")   # the first body
    rates = [k for k in names if k.startswith(f"{first}_") and k.endswith("_rad_per_s")
             and np.ptp(runs["rigid"][k]) > 0]
    fig, axes = plt.subplots(len(forces) + len(rates), 1, figsize=(10, 2 + 2.5 * (len(forces) + len(rates))),
                             sharex=True, squeeze=False)
    for ax, key in zip(axes[:, 0], forces + rates):
        for name, style in (("rigid", "k-"), ("flexible", "C1-")):
            ax.plot(runs[name]["time_s"], runs[name][key], style, lw=0.6, label=name)
        ax.set_ylabel(key.replace("_normal_force_N", " force (N)").replace("_rad_per_s", " (rad/s)"))
        ax.grid(alpha=0.3)
    axes[0, 0].legend()
    axes[-1, 0].set_xlabel("time (s)")
    buffer = io.BytesIO()   # drawn here, in memory: the report writes nothing into a run
    save_png(fig, buffer, layout=True)
    return base64.b64encode(buffer.getvalue()).decode()


def joint_figures(folder: Path, s, caption: str) -> list[str]:
    """Each clearance joint's figure with `caption`, then the run's warnings."""
    parts = [figure(png_data(folder / f"{name}.png"), f"Scene {folder.name}, joint {name}: {caption}")
             for name in s.clearance_joints if (folder / f"{name}.png").exists()]
    return parts + [f"<p class='note'>{folder.name}: {w}</p>" for w in s.warnings]


STRESS_OUTCOMES = ["complete", "suspect", "incomplete", "refused", "hang", "crash"]


def stress_part(bench_dir: Path) -> list[str]:
    """The multibody stress matrix (make stress): outcomes per sweep and the heat map."""
    path = bench_dir / "stress_reduced.csv"
    if not path.exists():
        return []
    parts = ["<h3>Stress matrix: multibody (make stress)</h3>",
             "<p>The Flores slider-crank over one crank revolution, one parameter swept at a "
             "time (contact modulus, clearance, restitution, drive speed), every friction law at "
             "mu 0, 0.2, 0.8, every damping law, every integrator at its defaults; each point a "
             "<code>pinbore reduced</code> run under a wall-clock limit. Criterion: no NaN, no "
             "hang, no crash, no complete run whose numbers break the verdict's thresholds "
             "(bench/stress_reduced.csv).</p>",
             outcome_counts(path, STRESS_OUTCOMES)]
    if (bench_dir / "stress.png").exists():
        parts.append(figure(png_data(bench_dir / "stress.png"),
                            "Stress matrix: one strip per sweep, a cell per point coloured by "
                            "outcome; a crossed cell failed the criterion (bench/stress.png)."))
    return parts


# what the report reads of each analysis' summary.json
DYNAMICS_KEYS = {"poincare": ("kind", "period", "lyapunov_per_s", "wall_time_s"),
                 "bifurcation": ("counts", "wall_time_s"), "design": ("band", "wall_time_s")}


def check_bifurcation_table(path: Path, summary: dict) -> None:
    """bifurcation.csv read and checked against its summary: each swept value's class, as
    many of each as summary.json counts."""
    from pinbore.reduced.dynamics import plots, studies   # noqa: PLC0415

    classes = {}
    for row in plots.read_table(path, studies.BIFURCATION_COLUMNS):
        classes.setdefault(row["value"], row["kind"])
    counts = {k: list(classes.values()).count(k) for k in sorted(set(classes.values()))}
    if counts != summary["counts"]:
        raise InputError(f"{path}: kind: its points' classes {counts} are not those of "
                         f"summary.json {summary['counts']} (run pinbore dynamics again)")


def dynamics_section(build_dir: Path, bench_dir: Path) -> str:
    """Nonlinear dynamics: Poincare map, bifurcation diagram, design map, continued
    responses (build/dynamics), and the continued responses too long for `make`, which
    `make bench` writes (bench_dir/continuation_<scene>/)."""
    folder = build_dir / "dynamics"
    parts = ["<h2>Nonlinear dynamics of the slider-crank with clearance</h2>",
             "<p>Sampled once per crank revolution after a transient; points classified as "
             "periodic (with their period), quasi-periodic or chaotic (largest Lyapunov exponent "
             "by Benettin's renormalisation); design map: peak contact force and slider "
             "acceleration deviation from the ideal joint over clearance and speed.</p>"]
    if not folder.exists():
        return "".join(parts) + "<p class='note'>No results: run <code>make dynamics</code>.</p>"
    captions = {"poincare": "Poincare map of the journal centre",
                "bifurcation": "bifurcation diagram against the radial clearance",
                "design": "design map (white: thresholds)",
                "spatial_poincare": "Misaligned spatial slider-crank (bore tilted 1 deg): Poincare "
                                    "map of the journal centre across the bore",
                "spatial_bifurcation": "Misaligned spatial slider-crank: bifurcation diagram "
                                       "against the radial clearance"}
    for name, caption in captions.items():
        path = folder / name / "summary.json"
        if not path.exists():
            continue
        s = load_json(path, "dynamics")
        kind = name.removeprefix("spatial_")
        for key in DYNAMICS_KEYS[kind]:
            if key not in s:
                raise InputError(f"{path}: {key}: required key is missing (run pinbore "
                                 "dynamics again)")
        facts = {"poincare": lambda: f"{s['kind']}" + (f", period {s['period']}" if s["period"] else "")
                 + (f", largest Lyapunov exponent {s['lyapunov_per_s']:.4g} 1/s" if s["lyapunov_per_s"] else ""),
                 "bifurcation": lambda: ", ".join(f"{k}: {v} points" for k, v in s["counts"].items()),
                 "design": lambda: "; ".join(f"{speed} rpm: " + (f"{b['low_m'] * 1e3:.3g}-{b['high_m'] * 1e3:.3g} mm"
                                                                 if b["low_m"] is not None else "none")
                                             for speed, b in s["band"].items())}[kind]()
        if kind == "bifurcation":
            check_bifurcation_table(folder / name / "bifurcation.csv", s)
        if s.get("disagreement"):
            facts += f"; NOTE: {s['disagreement']}"
        png = folder / name / f"{kind}.png"
        if png.exists():
            parts.append(figure(png_data(png), f"{caption} ({facts}; {s['wall_time_s']:.1f} s)."))
    for path in sorted(folder.glob("continuation*/summary.json")):
        parts.append(continuation_part(path))
    for path in sorted(bench_dir.glob("continuation_*/summary.json")):
        parts.append(continuation_part(path, "computed by <code>make bench</code> "
                                               "(bench/continuation.py), not by <code>make</code>"))
    return "".join(parts)


CONTINUATION_KEYS = ("scene_file", "parameter", "start", "points", "converged", "reason", "bifurcations",
                     "start_floquet_multipliers", "start_stable", "seconds_per_point", "wall_time_s")


def continuation_part(path: Path, source: str = "") -> str:
    """The continued response of a scene (build/dynamics/continuation*/: make dynamics runs
    the impact oscillator's; `source` says where another came from): its figure, the
    periodic orbit at the scene's own value with its Floquet multipliers, and the
    bifurcations."""
    s = load_json(path, "dynamics")
    for key in CONTINUATION_KEYS:
        if key not in s:
            raise InputError(f"{path}: {key}: required key is missing (run pinbore dynamics again)")
    moduli = sorted((abs(complex(*m)) for m in s["start_floquet_multipliers"]), reverse=True)
    parts = [f"<h3>Response by continuation: {html.escape(Path(s['scene_file']).stem)}</h3>",
             f"<p class='note'>Results {source}.</p>" if source else "",
             f"<p>Periodic motions continued in {html.escape(s['parameter'])} (pseudo-arclength on "
             f"the period map, {s['points']} orbits, {s['seconds_per_point']:.2f} s an orbit); "
             f"stability from the Floquet multipliers. The orbit at the scene's own value "
             f"({s['start']:g}) is {'stable' if s['start_stable'] else 'unstable'}: multiplier moduli "
             + ", ".join(f"{m:.4g}" for m in moduli) + ".</p>"]
    png = path.parent / "response.png"
    if png.exists():
        parts.append(figure(png_data(png), "Response amplitude of the first clearance joint and its "
                            "largest contact force: continued branch (stable solid, unstable dashed), "
                            f"direct up- and down-sweeps, bifurcations ({s['wall_time_s']:.1f} s)."))
    rows = [[b["kind"].replace("_", " "), f"{b['value']:.6g}", f"{b['amplitude_m'] * 1e3:.4g}",
             ", ".join(f"{abs(complex(*m)):.3g}" for m in sorted(b["floquet_multipliers"],
                                                                 key=lambda m: -abs(complex(*m)))[:3])]
            for b in s["bifurcations"]]
    if rows:
        parts.append(table(["bifurcation", s["parameter"], "amplitude (mm)", "largest multiplier moduli"], rows))
    if not s["converged"]:
        parts.append(note(f"The branch stopped: {html.escape(s['reason'])}"))
    for warning in s.get("warnings", []):
        parts.append(note(html.escape(warning)))
    return "".join(parts)
