"""The report's FE section: meshes, load-approach curves, validation against Persson, pressures."""

import csv
import html
from pathlib import Path

import numpy as np

from pinbore.core.figures import plt
from pinbore.core.html import figure, figure_data, note, outcome_counts, png_data, table
from pinbore.core.scene import load_json
from pinbore.fem import curve as fe_curve
from pinbore.fem.scene import FemScene
from pinbore.laws.elastic import persson_half_angle, persson_half_angles


def joint_of(result):
    """The contact-law joint of the scene an FE run recorded in its result.json."""
    return FemScene.model_validate(result["scene"]).joint


def similar(scene) -> bool:
    return scene["materials"]["pin"] == scene["materials"]["bore"]


def load_runs(build_dir: Path):
    """(scene name, result.json, curve.csv (pinbore.fem.curve.Curve), folder) of every FE run."""
    runs = []
    for result in sorted((build_dir / "fem").glob("*/result.json")):
        folder = result.parent
        runs.append((folder.name, load_json(result, "fem"),
                     fe_curve.read(folder / "curve.csv"), folder))
    return runs


def curves_figure(runs) -> str:
    fig, ax = plt.subplots(figsize=(9, 6))
    ax.set_prop_cycle(color=plt.cm.tab20.colors)
    for name, result, curve, _ in runs:
        push = curve.only("push")
        ax.plot(push.approach * 1e6, push.force / 1e3, "o-", ms=3,
                label=f"{name} (c = {joint_of(result).clearance * 1e6:.0f} um)")
    ax.set_xlabel("approach beyond first touch (um)")
    ax.set_ylabel("force per length (kN/m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    return figure_data(fig)


def persson_figure(runs) -> tuple[str, list]:
    """FE half-angle against load, beside the Persson closed form, for similar materials."""
    fig, ax = plt.subplots(figsize=(8, 5))
    rows = []
    load = np.geomspace(1e-4, 3, 300)
    ax.plot(load, [np.degrees(persson_half_angle(x)) for x in load], "k-", lw=1,
            label="Persson / Ciavarella-Decuzzi (infinite plate)")
    for name, result, curve, _ in runs:
        push = curve.only("push")
        if not similar(result["scene"]) or not push.points or result.get("worn"):
            continue   # (a worn joint is no round joint of its clearance)
        joint = joint_of(result)
        angle = push.half_angle
        ax.plot(push.force / (joint.e_star * joint.clearance), angle, "o", ms=4,
                label=f"FE {name}")
        closed = np.degrees(persson_half_angles(push.force, joint))
        rows.append([name, f"{angle.min():.1f}-{angle.max():.1f}",
                     f"{np.max(np.abs(angle - closed)):.2f}"])
    ax.set_xscale("log")
    ax.set_xlabel("P / (E* c)")
    ax.set_ylabel("contact half-angle (deg)")
    ax.grid(alpha=0.3)
    ax.legend()
    return figure_data(fig), rows


WEAR_KEYS = ("wear_file", "bore_frame_deg", "pin_frame_deg")


def round_twin(result, runs):
    """The run of the round joint a worn run wore: the same geometry but its wear, materials
    and contact (any load direction: a round joint's curve does not depend on it), or None."""
    def unworn(scene):
        g = {k: v for k, v in scene["geometry"].items() if k not in WEAR_KEYS}
        return g, scene["materials"], scene["contact"]

    return next((run for run in runs if not run[1].get("worn")
                 and unworn(run[1]["scene"]) == unworn(result["scene"])), None)


def worn_part(runs) -> list[str]:
    """Each worn joint's curve (geometry.wear_file) beside that of the round joint it wore:
    force, stiffness and contact arc at the worn run's largest approach."""
    pairs = [(run, round_twin(run[1], runs)) for run in runs if run[1].get("worn")]
    pairs = [(worn, twin) for worn, twin in pairs if twin is not None]
    if not pairs:
        return []
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
    rows = []
    for k, ((name, result, curve, _), (twin, _, round_curve, _)) in enumerate(pairs):
        worn, new = curve.only("push"), round_curve.only("push")
        if worn.points < 2 or new.points < 2:
            continue
        axes[0].plot(worn.approach * 1e6, worn.force / 1e3, "o-", ms=3, color=f"C{k}", label=f"{name} (worn)")
        axes[0].plot(new.approach * 1e6, new.force / 1e3, "s--", ms=3, color=f"C{k}", alpha=0.6,
                     label=f"{twin} (new)")
        axes[1].plot(worn.approach * 1e6, worn.half_angle, "o-", ms=3, color=f"C{k}")
        axes[1].plot(new.approach * 1e6, new.half_angle, "s--", ms=3, color=f"C{k}", alpha=0.6)
        d = min(worn.approach[-1], new.approach[-1])
        force = [np.interp(d, c.approach, c.force) for c in (worn, new)]
        slope = [np.interp(d, c.approach[1:], np.diff(c.force) / np.diff(c.approach)) for c in (worn, new)]
        angle = [np.interp(d, c.approach, c.half_angle) for c in (worn, new)]
        w = result["worn"]
        rows.append([name, twin, f"{w['bore_max_depth_m'] * 1e6:.1f} / {w['pin_max_depth_m'] * 1e6:.1f}",
                     f"{w['first_touch_m'] * 1e6:.1f} / {joint_of(result).clearance * 1e6:.1f}",
                     f"{d * 1e6:.3g}", f"{force[0] / force[1]:.3f}", f"{slope[0] / slope[1]:.3f}",
                     f"{angle[0]:.1f} / {angle[1]:.1f}"])
    axes[0].set_ylabel("force per length (kN/m)")
    axes[1].set_ylabel("contact half-angle (deg)")
    for ax in axes:
        ax.set_xlabel("approach beyond first touch (um)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    return ["<h3>Worn joints</h3>", figure(figure_data(fig), (
                "The FE of joints worn by <code>pinbore wear</code> (geometry.wear_file: the bore "
                "and the pin meshed on their worn profiles) beside the round joints they wore: "
                "force and contact half-angle against the approach beyond the worn surfaces' "
                "first touch.")),
            table(["worn scene", "new scene", "deepest wear bore / pin (um)",
                   "first touch worn / c (um)", "at approach (um)", "force worn / new",
                   "stiffness dF/d(approach) worn / new", "half-angle worn / new (deg)"], rows)]


def friction_figure(runs) -> str | None:
    """Friction torque (or tangential force) and stick fraction after the push, per scene."""
    programmes = {"rotate": "rotation_deg", "slide": "tangential_push"}
    slides = [(name, result, curve.only(stage), stage) for name, result, curve, _ in runs
              for stage, key in programmes.items() if result["scene"]["load"].get(key)]
    if not slides:
        return None
    fig, axes = plt.subplots(1, len(slides), figsize=(7 * len(slides), 4.5), squeeze=False)
    for ax, (name, result, curve, stage) in zip(axes[0], slides):
        mu = result["scene"]["contact"]["friction"]
        if stage == "rotate":
            x, y = curve.rotation, curve.friction_torque
            ax.set_xlabel("rotation of the hub (deg)")
            ax.set_ylabel("friction torque (N m/m)")
        else:
            x, y = curve.tangential_push * 1e6, curve.tangential_force
            ax.set_xlabel("tangential push of the hub (um)")
            ax.set_ylabel("tangential force (N/m)")
        ax.plot(x, y, "o-", ms=3, color="C0")
        twin = ax.twinx()
        twin.plot(x, curve.stick_fraction, "s--", ms=3, color="C1")
        twin.set_ylabel("fraction of the contact arc stuck", color="C1")
        twin.set_ylim(-0.05, 1.05)
        ax.set_title(f"{name} (mu = {mu:g})")
        ax.grid(alpha=0.3)
    return figure_data(fig)


PICTURES = {   # the pictures of a run and their captions (scene name, result.json)
    "contact.png": lambda name, r: (
        f"Scene {name}: deformed contact zone coloured by von Mises stress at the largest "
        f"approach, and the contact pressure along the bore at every load step."),
    "pressure_map.png": lambda name, r: (
        f"Scene {name} (3D, {r['dofs']} dofs, {html.escape(r['mesh']['symmetry'])}): contact "
        f"pressure on the pin at the end of the run."),
    "axial_profile.png": lambda name, r: (
        f"Scene {name}: peak pressure and line load along the axis, every load step."),
}


def run_pictures(runs) -> list[str]:
    return [figure(png_data(folder / picture), caption(html.escape(name), result))
            for name, result, _, folder in runs for picture, caption in PICTURES.items()
            if (folder / picture).exists()]


METHOD = ("Plane strain (2D) or 3D, P1 elements, both bodies elastic. Contact: node-to-surface "
          "gap between the pin nodes and the curved bore, penalty or augmented Lagrangian "
          "(Uzawa), Coulomb friction with a return map and an active-set Newton (PETSc SNES, "
          "MUMPS) with load-step cutbacks. The approach is the hub displacement beyond first "
          "touch; the force is the hub reaction along the load, per unit length in 2D, of the "
          "whole pin in 3D.")


def section(build_dir: Path, bench_dir: Path) -> str:
    runs = load_runs(build_dir)
    plane = [run for run in runs if run[2].dim == 2]   # forces per unit length (N/m)
    parts = ["<h2>Finite-element contact</h2>", f"<p>{METHOD}</p>"]
    if not runs:
        return "".join(parts + [note("No FE results under build/fem: run <code>make fem</code>.")]
                       + stress_part(bench_dir))
    parts.append(table(
        ["scene", "method", "c (um)", "dofs", "steps", "Newton its/step (median)",
         "max gap violation (m)", "wall time (s)", "status"],
        [[name, r["contact"]["method"], f"{joint_of(r).clearance * 1e6:g}", r["dofs"],
          r["steps_converged"], f"{np.median(r['newton_iterations']):g}",
          f"{r['max_gap_violation_m']:.2e}", f"{r['wall_time_s']['total']:.2f}", r["status"]]
         for name, r, _, _ in runs]))
    parts.append(figure(curves_figure(plane),
                        "Force per unit length against approach, every shipped FE scene "
                        "(build/fem/&lt;scene&gt;/curve.csv)."))
    data, rows = persson_figure(plane)
    parts.append(figure(data, "Validation: contact half-angle against the dimensionless load, "
                              "FE (similar materials) beside the Persson conformal solution for a "
                              "pin in an infinite plate. The FE model has a housing of 20 radii and "
                              "a rigid hub of 0.2 radius, which stiffens the pin: expect the FE "
                              "angle up to about 1 deg below the closed form."))
    if rows:
        parts.append(table(["scene", "FE half-angle range (deg)", "max |FE - Persson| (deg)"], rows))
    friction = friction_figure(plane)
    if friction:
        parts.append(figure(friction, "Coulomb friction after the push: the hub turns the pin "
                                      "(or pushes it sideways) with the approach held. The arc "
                                      "sticks, slips from its edges inwards, then slips whole; "
                                      "the full-slip torque equals mu R int p ds within 0.1 % "
                                      "(tests/test_fem_friction.py)."))
    parts += worn_part(plane)
    parts += run_pictures(runs)
    for preview in sorted((build_dir / "mesh").glob("*/preview.png")):
        parts.append(figure(png_data(preview), f"Mesh of scene {html.escape(preview.parent.name)}: "
                                               "whole model, pin and bore, contact arc."))
    captions = {"fem2d": "Wall time against the error in force and half-angle, 2D FE, for "
                         "several mesh sizes and both methods (bench/fem2d.csv).",
                "fem3d": "3D FE: wall time against the force error over mesh levels, on 1 and "
                         "2 MPI ranks, and the cost of friction (bench/fem3d.csv)."}
    for name, caption in captions.items():
        bench = bench_dir / f"{name}.csv"
        if bench.exists():
            with open(bench, newline="") as f:
                rows = list(csv.reader(f))
            parts.append(f"<h3>Benchmark {name}: run time against error (make bench)</h3>")
            parts.append(table(rows[0], rows[1:]))
            if (bench_dir / f"{name}.png").exists():
                parts.append(figure(png_data(bench_dir / f"{name}.png"), caption))
    parts += stress_part(bench_dir)
    return "".join(parts)


def stress_part(bench_dir: Path) -> list[str]:
    """The FE stress matrix (make stress): outcomes per sweep."""
    stress = bench_dir / "stress_fem.csv"
    if not stress.exists():
        return []
    return ["<h3>Stress matrix: 2D FE (make stress)</h3><p>The default scene with 4 load steps, "
            "one parameter swept at a time (c/R, modulus ratio, Poisson's ratio, approach, "
            "penalty factor with both methods, mu 0.8 with a rotation); each point a "
            "<code>pinbore fem</code> run under a wall-clock limit (bench/stress_fem.csv; heat "
            "map in the reduced-model section).</p>",
            outcome_counts(stress, ["complete", "incomplete", "refused", "hang", "crash"])]
