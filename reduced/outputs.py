"""Outputs of a reduced run: the time series, the summary (peaks, counters, energy balance,
constraint drift) and the plots."""

import csv
import math

import numpy as np

from pinbore.core.figures import plt, save_png
from pinbore.laws import tables
from pinbore.laws.dissipative import hysteresis_force
from pinbore.reduced import kernel
from pinbore.reduced.model import calibrated_restitution
from pinbore.reduced.layout import (
    CONTINUOUS, DISSIPATED, JOINT_BEARING_BODY, JOINT_BEARING_X, JOINT_BEARING_Y,
    JOINT_IMPACT, JOINT_JOURNAL_BODY, JOINT_JOURNAL_X, JOINT_JOURNAL_Y, LATCH, LOG_IMPULSE, LOG_JOINT,
    LOG_RATE, SPRING, STOP, TORSION_KIND, TORSION_STIFFNESS, WORK_IN)
from pinbore.reduced.summary import Summary


def per_step(model, run):
    """Columns at every accepted step of a Trajectory: body motion, joint quantities,
    energies, drift."""
    times, states = run.times, run.states
    nq, nj = model.nq, model.joints.shape[0]
    s = model.scene
    cols = {"time_s": times}
    acc = np.empty((times.size, nq))
    joint = np.zeros((times.size, nj, 6))   # ecc x, ecc y, penetration, F_n, F_t, elastic energy
    drift = np.empty(times.size)
    latched = run.latched
    for k in range(times.size):
        y = states[k]
        dy, normal = kernel.rhs_value(times[k], y, model.kernel_args(
            run.speeds[k, :nj], latched[k, :model.torsion.shape[0]], run.modes[k, :nj]))
        acc[k] = dy[nq:2 * nq]
        _, _, phi, _ = kernel.constraints(times[k], y[:nq], y[nq:2 * nq], model.revolute,
                                          model.prismatic, model.drive, 0.0)
        drift[k] = np.max(np.abs(phi), initial=0.0)
        for j in range(nj):
            row = model.joints[j]
            bx, by = kernel.point(y[:nq], int(row[JOINT_BEARING_BODY]), row[JOINT_BEARING_X],
                                  row[JOINT_BEARING_Y])
            jx, jy = kernel.point(y[:nq], int(row[JOINT_JOURNAL_BODY]), row[JOINT_JOURNAL_X],
                                  row[JOINT_JOURNAL_Y])
            if int(row[JOINT_IMPACT]) == CONTINUOUS:
                c = kernel.joint_forces(y[:nq], y[nq:2 * nq], row, run.speeds[k, j], model.grid_log0,
                                        model.grid_step, model.tables[j], y)
                joint[k, j] = (jx - bx, jy - by, c.delta, c.f_n, c.f_t, model.elastic_energy(j, c.delta))
            else:   # rigid impacts: the force of a held contact is its multiplier
                delta = kernel.joint_kinematics(y[:nq], y[nq:2 * nq], row).delta
                joint[k, j] = (jx - bx, jy - by, delta, normal[j], 0.0, 0.0)
    for b, body in enumerate(s.bodies):
        for i, (what, unit) in enumerate((("x", "m"), ("y", "m"), ("angle", "rad"))):
            cols[f"{body.name}_{what}_{unit}"] = states[:, 3 * b + i]
        for i, (what, unit) in enumerate((("vx", "m_per_s"), ("vy", "m_per_s"), ("omega", "rad_per_s"))):
            cols[f"{body.name}_{what}_{unit}"] = states[:, nq + 3 * b + i]
        for i, (what, unit) in enumerate((("ax", "m_per_s2"), ("ay", "m_per_s2"), ("alpha", "rad_per_s2"))):
            cols[f"{body.name}_{what}_{unit}"] = acc[:, 3 * b + i]
    for j, c in enumerate(s.clearance_joints):
        for i, key in enumerate(("ecc_x_m", "ecc_y_m", "penetration_m", "normal_force_N",
                                 "friction_force_N")):
            cols[f"{c.name}_{key}"] = joint[:, j, i]
    masses = 1 / model.minv
    qd = states[:, nq:2 * nq]
    kinetic = 0.5 * np.sum(masses * qd**2, axis=1)
    m_body = masses[0::3]
    potential = -np.sum(m_body * (model.gravity[0] * states[:, 0:nq:3] + model.gravity[1] * states[:, 1:nq:3]), axis=1)
    for r, row in enumerate(model.torsion):   # springs, engaged stops and latches: 1/2 k angle^2
        angle = np.array([kernel.relative_angle(y[:nq], y[nq:2 * nq], row).angle for y in states])
        engaged = {SPRING: np.ones_like(angle, bool), STOP: angle > 0,
                   LATCH: latched[:, r] > 0}[int(row[TORSION_KIND])]
        potential = potential + np.where(engaged, 0.5 * row[TORSION_STIFFNESS] * angle**2, 0.0)
    energy = {"kinetic": kinetic, "potential": potential, "elastic": joint[:, :, 5].sum(axis=1),
              "dissipated": states[:, 2 * nq + DISSIPATED], "work_in": states[:, 2 * nq + WORK_IN]}
    return cols, energy, drift


def hermite_basis(x: np.ndarray):
    """The cubic Hermite basis on [0, 1] at the points x, and its slopes: two (4, n) arrays
    whose rows weigh y0, h y0', y1, h y1' (a step of size h from y0 to y1)."""
    values = np.array([2 * x**3 - 3 * x**2 + 1, x**3 - 2 * x**2 + x, -2 * x**3 + 3 * x**2,
                       x**3 - x**2])
    slopes = np.array([6 * x**2 - 6 * x, 3 * x**2 - 4 * x + 1, -6 * x**2 + 6 * x, 3 * x**2 - 2 * x])
    return values, slopes


def refined_peak(model, j, run, k):
    """The peak normal force of joint j near accepted step k, refined between the steps
    k-1..k+1 by cubic Hermite interpolation of the penetration (delta and its rate at both ends
    of each step): (peak force N, its time s)."""
    times, states, speeds = run.times, run.states, run.speeds
    nq, row = model.nq, model.joints[j]
    best = (0.0, float(times[k]))
    x = np.linspace(0, 1, 201)
    values, slopes = hermite_basis(x)
    for a in range(max(k - 1, 0), min(k + 1, times.size - 1)):
        h = times[a + 1] - times[a]
        ends = [kernel.joint_kinematics(states[i, :nq], states[i, nq:2 * nq], row) for i in (a, a + 1)]
        weights = np.array([ends[0].delta, ends[0].rate * h, ends[1].delta, ends[1].rate * h])
        delta, rate = weights @ values, weights @ slopes / h
        for i in np.flatnonzero(delta > 0):
            f_el = tables.table_force(delta[i], model.grid_log0, model.grid_step, model.tables[j])
            force = hysteresis_force(f_el, rate[i], speeds[a + 1, j], kernel.joint_chi(row, speeds[a + 1, j]))
            if force > best[0]:
                best = (force, float(times[a] + x[i] * h))
    return best


def sample(model, run, columns=per_step):
    """Per-step columns (`columns`: per_step, or the spatial model's) interpolated to the
    output sample times (and the per-step data)."""
    cols, energy, drift = columns(model, run)
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


def summary(model, series, run, status_text, scene_file) -> Summary:
    """The run's summary (reduced/summary.py) from its series (`sample`) and the Trajectory."""
    return summary_of(model, series, run, status_text, scene_file, joint_peaks(model, series, run),
                      impact_speeds(model, run))


def impact_speeds(model, run) -> dict:
    """The impact speeds (m/s) of each clearance joint's logged onsets (a spatial joint's
    radial and axial), by joint name."""
    return {c.name: list(run.impacts[run.impacts[:, LOG_JOINT] == j, LOG_RATE])
            for j, c in enumerate(model.scene.clearance_joints)}


def joint_peaks(model, series, run) -> dict:
    """Each clearance joint's peaks and impacts (summary.JointPeaks) of a planar run."""
    joints = {}
    for j, c in enumerate(model.scene.clearance_joints):
        force = series["steps"][f"{c.name}_normal_force_N"]
        if c.impact == "continuous":
            peak, when = refined_peak(model, j, run, int(np.argmax(force)))
        else:
            peak, when = float(np.max(force)), float(run.times[np.argmax(force)])
        mine = run.impacts[run.impacts[:, LOG_JOINT] == j]
        joints[c.name] = {"peak_normal_force_N": peak, "time_of_peak_s": when,
                          "impacts": int(mine.shape[0]),
                          "peak_impact_speed_m_per_s": float(np.max(mine[:, LOG_RATE], initial=0.0)),
                          "peak_impulse_N_s": float(np.max(mine[:, LOG_IMPULSE], initial=0.0)),
                          "peak_penetration_m": float(np.max(series["steps"][f"{c.name}_penetration_m"], initial=0.0)),
                          "peak_friction_force_N": float(np.max(np.abs(series["steps"][f"{c.name}_friction_force_N"]), initial=0.0)),
                          "clearance_m": c.bearing_radius - c.journal_radius}
    return joints


def summary_of(model, series, run, status_text, scene_file, joints, impact_speeds=None) -> Summary:
    """The summary of a run (planar or spatial) from its series, Trajectory and joint peaks
    (and the impact speeds per joint, m/s, that a calibrated restitution is checked on)."""
    counters, status = run.counters, run.status
    e = series["energy"]
    total = e["kinetic"] + e["potential"] + e["elastic"] + e["dissipated"] - e["work_in"]
    scale = max(float(np.max(e["kinetic"])), 1e-300)
    return Summary.model_validate({
        "status": "complete" if status == kernel.OK else "incomplete",
        "stop": None if status == kernel.OK else {"time_s": run.t_end, "reason": status_text},
        "duration_s": model.scene.duration, "time_reached_s": run.t_end,
        "integrator": model.scene.integrator.method,
        "clearance_joints": joints,
        "impacts": int(counters[3]),
        "steps": int(counters[0]), "rejected_steps": int(counters[1]),
        "rhs_evaluations": int(counters[2]), "wall_time_s": run.seconds,
        "compile_time_s": run.compile_seconds,
        "energy_balance": {"max_residual_J": float(np.max(np.abs(total - total[0]))),
                           "relative_to_peak_kinetic": float(np.max(np.abs(total - total[0])) / scale),
                           "dissipated_J": float(e["dissipated"][-1]),
                           "work_in_J": float(e["work_in"][-1])},
        "constraint_drift_max": float(np.max(series["drift"])),
        "warnings": validity_warnings(model, joints, impact_speeds or {}),
        "scene_file": scene_file,
    })


def validity_warnings(model, joints, impact_speeds) -> list[str]:
    """Calibrated laws used beyond the approaches they were calibrated on, a calibrated
    restitution beyond the impact speeds it was fitted on (one line per joint)."""
    out = []
    for c in model.scene.clearance_joints:
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


def plots(folder, model, series, twin) -> None:
    """Prismatic body's acceleration against the driven angle (with the ideal joint), journal
    orbits inside the clearance circle, contact forces."""
    s = model.scene
    cols = series["steps"]
    angle = None
    if s.drive:
        angle = np.degrees(cols[f"{s.drive.body}_angle_rad"] - math.radians(s.drive.angle0_deg))
    slider = next((j for j in s.joints if j.type == "prismatic"), None)
    if slider and angle is not None:
        a = math.radians(slider.axis_deg)
        along = lambda c: c[f"{slider.body}_ax_m_per_s2"] * math.cos(a) + c[f"{slider.body}_ay_m_per_s2"] * math.sin(a)  # noqa: E731
        fig, ax = plt.subplots(figsize=(10, 4.5))
        ax.plot(angle, along(cols), lw=0.6, label="clearance joint")
        if twin is not None:
            t_model, t_run = twin
            t_cols = per_step(t_model, t_run)[0]
            ax.plot(np.degrees(t_cols[f"{s.drive.body}_angle_rad"] - math.radians(s.drive.angle0_deg)),
                    along(t_cols), "k--", lw=1, label="ideal joint")
        ax.set_xlabel(f"{s.drive.body} angle (deg)")
        ax.set_ylabel(f"{slider.body} acceleration (m/s^2)")
        ax.grid(alpha=0.3)
        ax.legend()
        save_png(fig, folder / "acceleration.png", layout=True)
    if s.drive is None and twin is not None:
        body = s.bodies[0].name
        t_model, t_run = twin
        t_cols = per_step(t_model, t_run)[0]
        fig, (ax, bx) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
        ax.plot(cols["time_s"], cols[f"{body}_omega_rad_per_s"], lw=0.6, label="clearance joint")
        ax.plot(t_cols["time_s"], t_cols[f"{body}_omega_rad_per_s"], "k--", lw=1, label="ideal joint")
        ax.set_ylabel(f"{body} attitude rate (rad/s)")
        ax.grid(alpha=0.3)
        ax.legend()
        ideal = np.interp(cols["time_s"], t_cols["time_s"], t_cols[f"{body}_omega_rad_per_s"])
        bx.plot(cols["time_s"], cols[f"{body}_omega_rad_per_s"] - ideal, lw=0.6)
        bx.set_ylabel("difference (rad/s)")
        bx.set_xlabel("time (s)")
        bx.grid(alpha=0.3)
        save_png(fig, folder / "attitude.png", layout=True)
    for c in s.clearance_joints:
        fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5))
        clearance = c.bearing_radius - c.journal_radius
        ring = np.linspace(0, 2 * np.pi, 200)
        ax.plot(clearance * np.cos(ring) * 1e3, clearance * np.sin(ring) * 1e3, "k-", lw=1)
        ax.plot(cols[f"{c.name}_ecc_x_m"] * 1e3, cols[f"{c.name}_ecc_y_m"] * 1e3, lw=0.6)
        ax.set_aspect("equal")
        ax.set_xlabel("journal centre x (mm)")
        ax.set_ylabel("journal centre y (mm)")
        ax.set_title(f"{c.name}: journal centre inside the clearance circle")
        x = angle if angle is not None else cols["time_s"]
        bx.plot(x, cols[f"{c.name}_normal_force_N"], lw=0.6)
        bx.set_xlabel(f"{s.drive.body} angle (deg)" if angle is not None else "time (s)")
        bx.set_ylabel("normal contact force (N)")
        bx.grid(alpha=0.3)
        save_png(fig, folder / f"{c.name}.png", layout=True)
