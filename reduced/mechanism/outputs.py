"""The outputs of a mechanism run of any kind, written once: the per-step columns (the bodies'
motion, each clearance joint's penetrations and forces), the energy book, the peaks refined
between the steps, timeseries.csv, summary.json and the plots.

A clearance joint's columns come from its contacts (reduced.mechanism.model): its deepest
penetration and the normal and friction forces summed over its contacts across the joint (a
journal's or ball's one contact, a cylindrical journal's two ends with rigid impacts, a
slider's four corners), and its type's own (reduced.mechanism.joints, `columns`): a
cylindrical joint's shoulders are its axial contacts (in space every revolute-type joint has
the two axial columns, -inf and 0 without shoulders); in the plane a revolute joint also
gives its journal's offset from the bearing's centre; a slider gives its offset, its tilt
and each corner's penetration and forces too. The body columns are the body kind's
(reduced.mechanism.planar or .spatial `motion_columns`).

The energy book: kinetic (the body kind's), potential of gravity, of the torsion springs,
stops and latches (1/2 k angle^2 while engaged) and of the spring-dampers (1/2 k (L - L0)^2),
elastic of the contacts (U(delta) of each tabulated law exactly,
reduced.mechanism.model.table_energy; a sliced journal's slices with the far field's spring
L |d|^2 / (2 c_b)), dissipated, and the work of the constraints (the drive) and of the
harmonic loads (integrated with the motion).

The peak normal force of a joint whose contacts are continuous is refined between the steps
around the largest step value: on each step the state is the cubic Hermite interpolant of y
and f(y) at its two ends (third order; an impact's peak falls between steps of a few
microseconds) and the force is the engine's at 201 interpolated states. A joint with rigid
impacts reports the largest multiplier of its held contacts at the steps.
"""

import csv

import numpy as np

from pinbore.reduced.mechanism import joints, kernel, layout
from pinbore.reduced.mechanism.layout import (
    CONTACT_COMPLIANCE, CONTACT_IMPACT, CONTACT_KIND, CONTACT_LENGTH, CONTACT_SLICES, CONTINUOUS,
    DISSIPATED, LATCH, OK, LOG_IMPULSE, LOG_JOINT, LOG_RATE, SLICED, SPRING, STOP, TORSION_KIND,
    TORSION_STIFFNESS, WORK_IN)
from pinbore.reduced.mechanism.model import calibrated_restitution
from pinbore.reduced.mechanism.summary import Summary

REFINE_POINTS = 201


def roles(model, j) -> dict:
    """The rows of clearance joint j's contacts by role (its type's): "main" (across the
    joint: a journal, a ball, a slider's corners) and "axial" (a cylindrical joint's
    shoulders)."""
    return joints.of(model.joints[j]).roles(model.contact_rows[j])


def joint_force(r, normal):
    """The force a joint's peak is taken of: the larger of its main contacts' normal forces
    summed and its axial ones' (N; r: the joint's roles; normal: the contacts' normal
    forces, or a row of them per step)."""
    return np.maximum(np.sum(normal[..., r["main"]], axis=-1), np.sum(normal[..., r["axial"]], axis=-1))


def observed_steps(model, run) -> dict:
    """kernel.observe at every accepted step of a Trajectory, each with the law memory (impact
    speeds, latches, contact modes) it was taken with: per-step arrays by name (rates,
    bodies, depths, normals, frictions, offsets, directions: each contact's, a worn journal's
    the normal of its overlap's force; drift, kinetic, angles, stretches), and the args and
    work it used."""
    times, states = run.times, run.states
    n, nc, nt = times.size, model.contacts.shape[0], model.torsion.shape[0]
    args = model.args()
    work = kernel.workspace(args)
    kept = model.kind.bodies().RIGID_COLUMNS   # of a body's row: its rigid motion
    seen = {"rates": np.empty((n, states.shape[1])), "bodies": np.empty((n, work.bodies.shape[0], kept)),
            "depths": np.empty((n, nc)), "normals": np.empty((n, nc)), "frictions": np.empty((n, nc)),
            "offsets": np.zeros((n, nc, model.kind.dimension)),
            "directions": np.zeros((n, nc, model.kind.dimension)), "drift": np.empty(n),
            "kinetic": np.empty(n), "angles": np.empty((n, nt)),
            "stretches": np.empty((n, args.springs.shape[0]))}
    kernel.observe_steps(times, states, run.speeds, run.latched, run.modes, args, work, *seen.values())
    return seen | {"args": args, "work": work}


def per_step(model, run):
    """Columns at every accepted step of a Trajectory (reduced.mechanism.run): body motion,
    joint quantities; the energy book; the ideal joints' drift."""
    times, states = run.times, run.states
    n, nq = times.size, model.nq
    dimension = model.kind.dimension
    seen = observed_steps(model, run)
    args, work, rates, bodies = seen["args"], seen["work"], seen["rates"], seen["bodies"]
    depths, normals, frictions = seen["depths"], seen["normals"], seen["frictions"]
    drift, kinetic, angles, stretches = seen["drift"], seen["kinetic"], seen["angles"], seen["stretches"]
    elastic = elastic_energy(model, states, args, work, depths)
    cols = {"time_s": times} | model.kind.bodies().motion_columns(
        model, states[:, :nq], states[:, nq:2 * nq], rates[:, nq:2 * nq], bodies)
    for j, c in enumerate(model.joints):
        r = roles(model, j)
        main = r["main"]
        mine = {"penetration_m": depths[:, main].max(axis=1), "normal_force_N": normals[:, main].sum(axis=1),
                "friction_force_N": frictions[:, main].sum(axis=1)}
        mine = joints.of(c).columns(mine, r, seen)
        cols |= {f"{c.name}_{key}": v for key, v in mine.items()}
    potential = np.zeros(n)
    for b in range(len(model.names)):
        c = model.geometry.coordinate(b)
        potential -= model.base.masses[b] * (states[:, c:c + dimension] @ model.base.gravity)
    potential += model.kind.bodies().strain_energy(model, states[:, :nq])
    for r, row in enumerate(model.torsion):   # springs, engaged stops and latches
        engaged = {SPRING: np.ones(n, bool), STOP: angles[:, r] > 0,
                   LATCH: run.latched[:, r] > 0}[int(row[TORSION_KIND])]
        potential += np.where(engaged, 0.5 * row[TORSION_STIFFNESS] * angles[:, r] ** 2, 0.0)
    potential += 0.5 * (stretches ** 2) @ model.base.springs[:, layout.SPRING_STIFFNESS]
    energy = {"kinetic": kinetic, "potential": potential, "elastic": elastic,
              "dissipated": states[:, 2 * nq + DISSIPATED], "work_in": states[:, 2 * nq + WORK_IN]}
    return cols, energy, drift


def elastic_energy(model, states, args, work, depths) -> np.ndarray:
    """The elastic energy of every continuous contact at each state (J per row of states;
    depths: each contact's deepest penetration there, one row per state)."""
    total = np.zeros(states.shape[0])
    for k in range(model.contacts.shape[0]):
        row = model.contacts[k]
        if int(row[CONTACT_IMPACT]) != CONTINUOUS:
            continue
        if int(row[CONTACT_KIND]) != SLICED:
            total += model.elastic_energy(k, depths[:, k])
            continue
        approaches, weights = np.empty((2, states.shape[0], int(row[CONTACT_SLICES])))
        moved = np.array([kernel.slice_approaches(y, args, work, k, approaches[s], weights[s])
                          for s, y in enumerate(states)])
        total += np.sum(weights * model.elastic_energy(k, approaches), axis=1)
        if row[CONTACT_COMPLIANCE] > 0:
            total += row[CONTACT_LENGTH] * np.sum(moved**2, axis=1) / (2 * row[CONTACT_COMPLIANCE])
    return total


def hermite_basis(x: np.ndarray):
    """The cubic Hermite basis on [0, 1] at the points x, and its slopes: two (4, n) arrays
    whose rows weigh y0, h y0', y1, h y1' (a step of size h from y0 to y1)."""
    values = np.array([2 * x**3 - 3 * x**2 + 1, x**3 - 2 * x**2 + x, -2 * x**3 + 3 * x**2,
                       x**3 - x**2])
    slopes = np.array([6 * x**2 - 6 * x, 3 * x**2 - 4 * x + 1, -6 * x**2 + 6 * x, 3 * x**2 - 2 * x])
    return values, slopes


def between_steps(model, run, k, points=REFINE_POINTS):
    """The states around accepted step k as the outputs refine them: step k itself, then on
    each step from k-1 to k+1 the cubic Hermite interpolant of y and f(y) at its two ends
    at `points` fractions of it, as (t, y, args, work), args holding the law memory (impact
    speeds, latches, contact modes) the step was taken with."""
    times, states = run.times, run.states
    nc, nt = model.contacts.shape[0], model.torsion.shape[0]
    basis, _ = hermite_basis(np.linspace(0.0, 1.0, points))
    args = model.args()
    work = kernel.workspace(args)
    f0, f1 = np.empty(states.shape[1]), np.empty(states.shape[1])

    def remember(a):   # the memory of the step that ends at a
        args.speeds[:], args.latched[:] = run.speeds[a, :nc], run.latched[a, :nt]
        args.mode[:] = run.modes[a, :nc]
    remember(k)
    yield float(times[k]), states[k], args, work
    for a in range(max(k - 1, 0), min(k + 1, times.size - 1)):
        remember(a + 1)
        h = times[a + 1] - times[a]
        kernel.rhs(times[a], states[a], f0, args, work)
        kernel.rhs(times[a + 1], states[a + 1], f1, args, work)
        ys = basis.T @ np.array([states[a], h * f0, states[a + 1], h * f1])
        for i in range(points):
            yield float(times[a] + i / (points - 1) * h), ys[i], args, work


def refined_max(model, run, k, quantity, points=REFINE_POINTS):
    """The largest value of quantity(t, y, args, work) near accepted step k, refined between
    the steps k-1..k+1 on the cubic Hermite interpolant of the state (`between_steps`):
    (value, its time s)."""
    best = None
    for t, y, args, work in between_steps(model, run, k, points):
        value = quantity(t, y, args, work)
        if best is None or value > best[0]:
            best = (float(value), t)
    return best


def refined_peak(model, j, run, k, points=REFINE_POINTS):
    """The peak normal force of clearance joint j (joint_force) near accepted step k,
    refined between the steps (refined_max): (peak force N, its time s)."""
    r = roles(model, j)
    nc = model.contacts.shape[0]
    dy = np.empty(run.states.shape[1])

    def force(t, y, args, work):
        kernel.rhs(t, y, dy, args, work)
        return joint_force(r, work.normal[:nc])
    return refined_max(model, run, k, force, points)


def joint_peak(model, j, run, force):
    """Clearance joint j's largest normal force over a run and its time (N, s): the largest of
    `force`, its joint_force at each accepted step, refined between the steps where its
    contacts are continuous (refined_peak)."""
    r = roles(model, j)
    k = int(np.argmax(force))
    continuous = all(int(model.contacts[i, CONTACT_IMPACT]) == CONTINUOUS for i in r["main"] + r["axial"])
    return refined_peak(model, j, run, k) if continuous else (float(force[k]), float(run.times[k]))


def sample(model, run):
    """Per-step columns interpolated to the output sample times (and the per-step data)."""
    cols, energy, drift = per_step(model, run)
    grid = np.arange(0.0, run.times[-1], model.scene.output.sample_time)
    grid = np.append(grid, run.times[-1]) if grid[-1] < run.times[-1] else grid
    sampled = {k: np.interp(grid, run.times, v) for k, v in cols.items()}
    return {"sampled": sampled, "steps": cols, "energy": energy, "drift": drift}


def write_timeseries(path, series) -> None:
    cols = series["sampled"]
    with open(path, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(cols)
        for row in zip(*cols.values()):
            out.writerow([f"{v:.9e}" for v in row])


def joint_peaks(model, series, run) -> dict:
    """Each clearance joint's peaks and impacts (summary.JointPeaks)."""
    joints = {}
    steps = series["steps"]
    for j, c in enumerate(model.joints):
        force = np.maximum(steps[f"{c.name}_normal_force_N"], steps.get(f"{c.name}_axial_force_N", 0.0))
        peak, when = joint_peak(model, j, run, force)
        mine = run.impacts[run.impacts[:, LOG_JOINT] == j]
        penetration = max(np.max(steps[f"{c.name}_penetration_m"], initial=0.0),
                          np.max(steps.get(f"{c.name}_axial_penetration_m", 0.0), initial=0.0), 0.0)
        joints[c.name] = {"peak_normal_force_N": peak, "time_of_peak_s": when,
                          "impacts": int(mine.shape[0]),
                          "peak_impact_speed_m_per_s": float(np.max(mine[:, LOG_RATE], initial=0.0)),
                          "peak_impulse_N_s": float(np.max(mine[:, LOG_IMPULSE], initial=0.0)),
                          "peak_penetration_m": float(penetration),
                          "peak_friction_force_N": float(np.max(np.abs(steps[f"{c.name}_friction_force_N"]), initial=0.0)),
                          "clearance_m": c.gap()}
    return joints


def impact_speeds(model, run) -> dict:
    """The impact speeds (m/s) of each clearance joint's logged onsets, by joint name."""
    return {c.name: list(run.impacts[run.impacts[:, LOG_JOINT] == j, LOG_RATE])
            for j, c in enumerate(model.joints)}


def summary(model, series, run, status_text, scene_file) -> Summary:
    """The run's summary (reduced.mechanism.summary) from its series (`sample`) and the
    Trajectory."""
    counters, status = run.counters, run.status
    joints = joint_peaks(model, series, run)
    e = series["energy"]
    total = e["kinetic"] + e["potential"] + e["elastic"] + e["dissipated"] - e["work_in"]
    scale = max(float(np.max(e["kinetic"])), 1e-300)
    return Summary.model_validate({
        "model": model.kind.name, "coordinates": model.kind.coordinates,
        "status": "complete" if status == OK else "incomplete",
        "stop": None if status == OK else {"time_s": run.t_end, "reason": status_text},
        "duration_s": model.scene.duration, "time_reached_s": run.t_end,
        "integrator": model.scene.integrator.method,
        "clearance_joints": joints,
        "impacts": int(counters[3]),
        "steps": int(counters[0]), "rejected_steps": int(counters[1]),
        "rhs_evaluations": int(counters[2]), "wall_time_s": run.seconds,
        "energy_balance": {"max_residual_J": float(np.max(np.abs(total - total[0]))),
                           "relative_to_peak_kinetic": float(np.max(np.abs(total - total[0])) / scale),
                           "dissipated_J": float(e["dissipated"][-1]),
                           "work_in_J": float(e["work_in"][-1])},
        "constraint_drift_max": float(np.max(series["drift"])),
        "warnings": validity_warnings(model, joints, impact_speeds(model, run)),
        "scene_file": scene_file,
    })


def validity_warnings(model, joints, impact_speeds) -> list[str]:
    """Calibrated laws used beyond the approaches they were calibrated on, a calibrated
    restitution beyond the impact speeds it was fitted on (one line per joint)."""
    out = []
    for c in model.joints:
        if getattr(c, "damping_law", None) == "calibrated" and model.calibration is not None:
            low, high = calibrated_restitution(c, model.calibration, "").speed_range_m_per_s
            speeds = impact_speeds.get(c.name, [])
            outside = [v for v in speeds if not low * (1 - 1e-9) <= v <= high * (1 + 1e-9)]
            if outside:
                out.append(f"{c.name}: {len(outside)} of {len(speeds)} impact speeds "
                           f"({min(outside):.3g}-{max(outside):.3g} m/s) outside the speeds "
                           f"({low:.3g}-{high:.3g} m/s) the calibrated restitution was fitted "
                           "on: e held at the nearer end")
        kind, _, name = (c.normal_law or "").partition(":")
        if kind in ("calibrated", "sliced") and model.calibration is not None:
            laws = model.calibration.laws if kind == "calibrated" else model.calibration.sliced
            low, high = laws[name].validity.approach_m
            if kind == "sliced":
                shortest, longest = laws[name].validity.length_m
                if not shortest * (1 - 1e-9) <= c.length <= longest * (1 + 1e-9):
                    out.append(f"{c.name}: length {c.length:.3g} m outside the lengths "
                               f"({shortest:.3g}-{longest:.3g} m) {c.normal_law} was calibrated "
                               "on: extrapolated")
            peak = joints[c.name]["peak_penetration_m"]
            if peak > high:
                out.append(f"{c.name}: peak penetration {peak:.3g} m beyond the calibrated range "
                           f"({low:.3g}-{high:.3g} m) of {c.normal_law}: extrapolated")
    return out


# ---- plots
def plots(folder, model, series, twin) -> None:
    """Per clearance joint its forces (and, a planar journal, its orbit inside the clearance
    circle; a slider, its corners'); with a drive and a slider on a prismatic joint, the
    slider's acceleration against the driven angle beside the ideal joints' (twin); without
    a drive, the first body's attitude rates against the ideal joints'."""
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415 (matplotlib only to draw)
    cols = series["steps"]
    back_end = model.kind.bodies()
    angle = back_end.drive_angle(model, cols)
    x, x_label = (angle, "driven angle (deg)") if angle is not None else (cols["time_s"], "time (s)")
    twin_cols = per_step(*twin)[0] if twin is not None else None
    slider = back_end.slider_acceleration(model, cols)
    if slider is not None and angle is not None:
        fig, ax = plt.subplots(figsize=(10, 4.5))
        ax.plot(angle, slider, lw=0.6, label="clearance joint")
        if twin_cols is not None:
            ax.plot(back_end.drive_angle(twin[0], twin_cols),
                    back_end.slider_acceleration(twin[0], twin_cols), "k--", lw=1, label="ideal joint")
        ax.set_xlabel(x_label)
        ax.set_ylabel("slider acceleration along its guide (m/s^2)")
        ax.grid(alpha=0.3)
        ax.legend()
        save_png(fig, folder / "acceleration.png", layout=True)
    if model.scene.drive is None and twin_cols is not None:
        body = model.names[0]
        rates = [key for key in cols if key.startswith(f"{body}_") and key.endswith("_rad_per_s")]
        fig, axes = plt.subplots(len(rates), 1, figsize=(10, 3 + 2.5 * len(rates)), sharex=True,
                                 squeeze=False)
        for ax, key in zip(axes[:, 0], rates):
            ax.plot(cols["time_s"], cols[key], lw=0.6, label="clearance joint")
            ax.plot(twin_cols["time_s"], twin_cols[key], "k--", lw=1, label="ideal joint")
            ax.set_ylabel(key.replace("_rad_per_s", " (rad/s)"))
            ax.grid(alpha=0.3)
        axes[0, 0].legend()
        axes[-1, 0].set_xlabel("time (s)")
        save_png(fig, folder / "attitude.png", layout=True)
    for j, c in enumerate(model.joints):
        joint_plot(folder, model, j, c, cols, x, x_label)
    points_plot(folder, model, cols, x, x_label)


def points_plot(folder, model, cols, x, x_label) -> None:
    """The output points' elastic displacement in their bodies' frames against the driven
    angle or time (points.png), when a flexible body has one."""
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415 (matplotlib only to draw)
    points = [p for p in model.scene.output.points if p.body in getattr(model.geometry, "flexible", {})]
    if not points:
        return
    fig, axes = plt.subplots(len(points), 1, figsize=(10, 1.5 + 2.5 * len(points)), sharex=True,
                             squeeze=False)
    for ax, p in zip(axes[:, 0], points):
        key = f"{p.body}_{p.name}"
        for axis in "xyz"[:model.kind.dimension]:
            ax.plot(x, cols[f"{key}_u{axis}_m"] * 1e3, lw=0.6, label=f"u{axis}")
        ax.set_ylabel(f"{key} (mm)")
        ax.grid(alpha=0.3)
        ax.legend()
    axes[0, 0].set_title("elastic displacement in the body's floating frame")
    axes[-1, 0].set_xlabel(x_label)
    save_png(fig, folder / "points.png", layout=True)


def joint_plot(folder, model, j, c, cols, x, x_label) -> None:
    """One clearance joint's picture: its forces against the driven angle or time; beside
    them a planar journal's centre inside its clearance circle, or a slider's offset across
    its guide and its tilt."""
    from pinbore.core.figures import plt, save_png   # noqa: PLC0415 (matplotlib only to draw)
    orbit = f"{c.name}_ecc_x_m" in cols
    slider = f"{c.name}_offset_m" in cols
    panels = 3 if slider else 2 if orbit else 1
    fig, axes = plt.subplots(1, panels, figsize=(5 * panels + 2, 5), squeeze=False)
    ax = axes[0, -1]
    if slider:
        cx = axes[0, 0]
        cx.plot(x, cols[f"{c.journal_body}_x_m"], lw=0.8)
        cx.set_xlabel(x_label)
        cx.set_ylabel(f"{c.journal_body}: centre of mass x (m)")
        cx.set_title(f"{c.name}: the slider's travel")
        cx.grid(alpha=0.3)
        bx = axes[0, 1]
        bx.plot(x, cols[f"{c.name}_offset_m"] * 1e3, lw=0.8, label="offset across the guide (mm)")
        bx.axhline(c.gap() * 1e3, color="k", lw=0.6, ls=":")
        bx.axhline(-c.gap() * 1e3, color="k", lw=0.6, ls=":")
        tilt = bx.twinx()
        tilt.plot(x, np.degrees(cols[f"{c.name}_tilt_rad"]), "C1", lw=0.8)
        tilt.set_ylabel("tilt against the guide (deg)", color="C1")
        bx.set_xlabel(x_label)
        bx.set_ylabel("offset across the guide (mm; dotted: the clearance)")
        bx.set_title(f"{c.name}: the slider in its guide")
        bx.grid(alpha=0.3)
    if orbit:
        bx = axes[0, 0]
        ring = np.linspace(0, 2 * np.pi, 200)
        bx.plot(c.gap() * np.cos(ring) * 1e3, c.gap() * np.sin(ring) * 1e3, "k-", lw=1)
        bx.plot(cols[f"{c.name}_ecc_x_m"] * 1e3, cols[f"{c.name}_ecc_y_m"] * 1e3, lw=0.6)
        bx.set_aspect("equal")
        bx.set_xlabel("journal centre x (mm)")
        bx.set_ylabel("journal centre y (mm)")
        bx.set_title(f"{c.name}: journal centre inside the clearance circle")
    corners = [key for key in cols if key.startswith(f"{c.name}_corner") and key.endswith("_normal_force_N")]
    if corners:
        for key in corners:
            ax.plot(x, cols[key], lw=0.6, label=key[len(c.name) + 1:].split("_")[0])
    else:
        ax.plot(x, cols[f"{c.name}_normal_force_N"], lw=0.6, label="across the joint")
        if f"{c.name}_axial_force_N" in cols and np.any(cols[f"{c.name}_axial_force_N"]):
            ax.plot(x, cols[f"{c.name}_axial_force_N"], lw=0.6, label="axial")
    ax.set_xlabel(x_label)
    ax.set_ylabel("normal contact force (N)")
    ax.set_title(c.name)
    ax.grid(alpha=0.3)
    ax.legend()
    save_png(fig, folder / f"{c.name}.png", layout=True)

