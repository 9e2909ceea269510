"""Outputs of a spatial run: the same files as a planar run (timeseries.csv, summary.json with
the same keys, plots), from the spatial kernel's states."""

import numpy as np

from pinbore.core.figures import plt, save_png
from pinbore.reduced import outputs, spatial_kernel
from pinbore.reduced.layout import DISSIPATED, LATCH, LOG_JOINT, LOG_RATE, SPRING, STOP, WORK_IN
from pinbore.reduced.layout import TORSION_KIND, TORSION_STIFFNESS
from pinbore.reduced.spatial_layout import (AXIAL, BODY_OMEGA, BODY_ROT, CHANNELS, CYLINDER, RADIAL, SJ_AXIAL_STIFFNESS,
                                            SJ_COMPLIANCE, SJ_KIND, SJ_LENGTH, SJ_SLICES)


def per_step(model, run):
    """Columns at every accepted step: body motion (position, Euler parameters, velocity,
    global angular velocity, accelerations), per clearance joint its deepest radial and axial
    penetrations and forces, energies and the ideal joints' drift."""
    times, states = run.times, run.states
    nq, nb, nj = model.nq, model.masses.size, model.joints.shape[0]
    cols = {"time_s": times}
    motion = np.zeros((times.size, nb, 19))
    joint = np.zeros((times.size, nj, 6))   # penetration, normal, axial pen., axial, friction, U
    drift = np.empty(times.size)
    kinetic = np.zeros(times.size)
    potential = np.zeros(times.size)
    for k in range(times.size):
        y = states[k]
        args = model.kernel_args(run.speeds[k, :CHANNELS * nj], run.latched[k, :model.torsion.shape[0]])
        dy, _ = spatial_kernel.rhs_value(times[k], y, args)
        work = spatial_kernel.workspace(args)
        spatial_kernel.body_states(y, args, work)
        m = spatial_kernel.fill_constraints(times[k], work, model.primitives, 0.0)
        drift[k] = np.max(np.abs(work.phi[:m]), initial=0.0)
        for b in range(nb):
            w = work.bodies[b, BODY_OMEGA:BODY_OMEGA + 3]
            rot = work.bodies[b, BODY_ROT:BODY_ROT + 9].reshape(3, 3)
            motion[k, b] = [*y[7 * b:7 * b + 7], *y[nq + 7 * b:nq + 7 * b + 3], *w,
                            *dy[nq + 7 * b:nq + 7 * b + 3], 0, 0, 0]
            inertia = rot @ model.inertia[b] @ rot.T
            kinetic[k] += 0.5 * model.masses[b] * y[nq + 7 * b:nq + 7 * b + 3] @ y[nq + 7 * b:nq + 7 * b + 3]
            kinetic[k] += 0.5 * w @ inertia @ w
            potential[k] -= model.masses[b] * np.asarray(model.scene.gravity) @ y[7 * b:7 * b + 3]
        force = np.zeros(6 * nb)
        for j in range(nj):
            row = model.joints[j]
            f_n, f_a, f_t, _ = spatial_kernel.joint_forces(
                force, work.bodies, row, model.tables[j], model.grid_log0, model.grid_step,
                args.speeds[CHANNELS * j + RADIAL], args.speeds[CHANNELS * j + AXIAL])
            depth = spatial_kernel.channel_depth(work.bodies, row, RADIAL).delta
            axial = spatial_kernel.channel_depth(work.bodies, row, AXIAL).delta
            energy = 0.0
            if int(row[SJ_KIND]) == CYLINDER:
                # the slices' local law, the far field's spring L |d|^2 / (2 c_b) (laws.sliced)
                approaches, weights = np.empty((2, int(row[SJ_SLICES])))
                moved = np.array(spatial_kernel.cylinder_slices(
                    work.bodies, row, model.tables[j], model.grid_log0, model.grid_step, approaches,
                    weights))
                for delta, weight in zip(approaches, weights):
                    energy += weight * model.elastic_energy(j, delta)
                if row[SJ_COMPLIANCE] > 0:
                    energy += row[SJ_LENGTH] * (moved @ moved) / (2 * row[SJ_COMPLIANCE])
                energy += 0.5 * row[SJ_AXIAL_STIFFNESS] * max(axial, 0.0) ** 2
            else:
                energy = model.elastic_energy(j, depth)
            joint[k, j] = (depth, f_n, axial, f_a, f_t, energy)
        for r, row in enumerate(model.torsion):
            angle = spatial_kernel.relative_angle(work.bodies, row)[0]
            engaged = {SPRING: True, STOP: angle > 0,
                       LATCH: run.latched[k, r] > 0}[int(row[TORSION_KIND])]
            potential[k] += 0.5 * row[TORSION_STIFFNESS] * angle**2 if engaged else 0.0
    keys = [("x", "m"), ("y", "m"), ("z", "m"), ("e0", "1"), ("e1", "1"), ("e2", "1"),
            ("e3", "1"), ("vx", "m_per_s"), ("vy", "m_per_s"), ("vz", "m_per_s"),
            ("wx", "rad_per_s"), ("wy", "rad_per_s"), ("wz", "rad_per_s"), ("ax", "m_per_s2"),
            ("ay", "m_per_s2"), ("az", "m_per_s2")]
    for b, name in enumerate(model.names):
        for i, (what, unit) in enumerate(keys):
            cols[f"{name}_{what}_{unit}"] = motion[:, b, i]
    for j, c in enumerate(model.scene.clearance_joints):
        for i, key in enumerate(("penetration_m", "normal_force_N", "axial_penetration_m",
                                 "axial_force_N", "friction_force_N")):
            cols[f"{c.name}_{key}"] = joint[:, j, i]
    energy = {"kinetic": kinetic, "potential": potential, "elastic": joint[:, :, 5].sum(axis=1),
              "dissipated": states[:, 2 * nq + DISSIPATED], "work_in": states[:, 2 * nq + WORK_IN]}
    return cols, energy, drift


def refined_peak(model, j, run, k, points=201):
    """The peak radial normal force of clearance joint j near accepted step k, refined
    between the steps k-1..k+1 (the planar model's reduced.outputs.refined_peak, for a state
    of any size): on each step the state is the cubic Hermite interpolant of y and f(y) at its
    two ends (third order, as the planar model's interpolant of the penetration), and the
    force is the kernel's at `points` interpolated states. (peak force N, its time s)"""
    times, states = run.times, run.states
    best = (0.0, float(times[k]))
    x = np.linspace(0.0, 1.0, points)
    basis, _ = outputs.hermite_basis(x)
    for a in range(max(k - 1, 0), min(k + 1, times.size - 1)):
        args = model.kernel_args(run.speeds[a + 1, :CHANNELS * model.joints.shape[0]],
                                 run.latched[a + 1, :model.torsion.shape[0]])
        h = times[a + 1] - times[a]
        f0 = spatial_kernel.rhs_value(times[a], states[a], args)[0]
        f1 = spatial_kernel.rhs_value(times[a + 1], states[a + 1], args)[0]
        ys = basis.T @ np.array([states[a], h * f0, states[a + 1], h * f1])
        for i in range(points):
            t = times[a] + x[i] * h
            force = spatial_kernel.rhs_value(t, ys[i], args)[1][CHANNELS * j + RADIAL]
            if force > best[0]:
                best = (float(force), float(t))
    return best


def sample(model, run):
    return outputs.sample(model, run, per_step)


def summary(model, series, run, status_text, scene_file):
    """summary.json's model (reduced/summary.py), the same keys as a planar run; the peak
    normal force is the largest at the accepted steps (radial or axial)."""
    joints = {}
    steps = series["steps"]
    for j, c in enumerate(model.scene.clearance_joints):
        force = np.maximum(steps[f"{c.name}_normal_force_N"], steps[f"{c.name}_axial_force_N"])
        k = int(np.argmax(force))
        mine = run.impacts[run.impacts[:, LOG_JOINT] == j]
        joints[c.name] = {"peak_normal_force_N": float(force[k]), "time_of_peak_s": float(run.times[k]),
                          "impacts": int(mine.shape[0]),
                          "peak_impact_speed_m_per_s": float(np.max(mine[:, LOG_RATE], initial=0.0)),
                          "peak_impulse_N_s": 0.0,
                          "peak_penetration_m": float(max(np.max(steps[f"{c.name}_penetration_m"], initial=0.0),
                                                          np.max(steps[f"{c.name}_axial_penetration_m"], initial=0.0), 0.0)),
                          "peak_friction_force_N": float(np.max(np.abs(steps[f"{c.name}_friction_force_N"]), initial=0.0)),
                          "clearance_m": c.bearing_radius - c.journal_radius}
    return outputs.summary_of(model, series, run, status_text, scene_file, joints,
                              outputs.impact_speeds(model, run))


def plots(folder, model, series, twin) -> None:
    """Per clearance joint its forces against time; without a drive, the first body's three
    attitude rates against the ideal joints' (twin)."""
    cols = series["steps"]
    for c in model.scene.clearance_joints:
        fig, ax = plt.subplots(figsize=(10, 4.5))
        if c.type == "cylindrical":
            ax.plot(cols["time_s"], cols[f"{c.name}_normal_force_N"], lw=0.6, label="radial")
            ax.plot(cols["time_s"], cols[f"{c.name}_axial_force_N"], lw=0.6, label="axial")
        else:
            ax.plot(cols["time_s"], cols[f"{c.name}_normal_force_N"], lw=0.6, label="ball on socket")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("contact force (N)")
        ax.set_title(c.name)
        ax.grid(alpha=0.3)
        ax.legend()
        save_png(fig, folder / f"{c.name}.png", layout=True)
    if model.scene.drive is None and twin is not None:
        body = model.names[0]
        t_cols = per_step(*twin)[0]
        fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
        for ax, axis in zip(axes, "xyz"):
            key = f"{body}_w{axis}_rad_per_s"
            ax.plot(cols["time_s"], cols[key], lw=0.6, label="clearance joint")
            ax.plot(t_cols["time_s"], t_cols[key], "k--", lw=1, label="ideal joint")
            ax.set_ylabel(f"{body} w{axis} (rad/s)")
            ax.grid(alpha=0.3)
        axes[0].legend()
        axes[-1].set_xlabel("time (s)")
        save_png(fig, folder / "attitude.png", layout=True)
