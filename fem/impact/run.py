"""`pinbore impact SCENE --out DIR`: the pin flies into the bore and rebounds
(fem.impact.solver); write history.csv, impact.json (fem.impact.file) and force_time.png."""

import platform
import sys
import time
from pathlib import Path

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
import numpy as np
from mpi4py import MPI
from tqdm import tqdm

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.core.figures import plt, save_png
from pinbore.core.output import atomic_directory
from pinbore.fem import model
from pinbore.fem.impact import file as impact_file
from pinbore.fem.impact.scene import ImpactScene
from pinbore.fem.impact.solver import ImpactStepper


def build(scene: ImpactScene, comm=MPI.COMM_WORLD):
    """The stepper of an impact scene on the mesh of its equivalent quasi-static scene:
    (stepper, elasticity, contact, sizing)."""
    fem_scene = scene.equivalent_fem_scene
    el, contact, material, sizing, data = model.bodies(fem_scene, comm)
    impact = scene.impact
    estimate = scene.estimate
    flight = scene.initial_gap / impact.speed
    stepper = ImpactStepper(
        el, contact, data.cell_tags, rho_pin=scene.materials.pin.density,
        rho_bore=scene.materials.bore.density, hub_radius=scene.geometry.hub_radius,
        hub_mass=impact.hub_mass, clearance=scene.geometry.clearance,
        direction=np.asarray(impact.direction), speed=impact.speed, dt=scene.dt,
        rho_inf=impact.spectral_radius, initial_gap=scene.initial_gap,
        t_end=flight + impact.max_contact_durations * estimate.duration,
        method=scene.contact.method, gap_tolerance=model.gap_tolerance(fem_scene),
        newton_max_it=scene.solver.newton_max_it, uzawa_max_it=scene.solver.uzawa_max_it,
        max_cutbacks=scene.solver.max_cutbacks,
        force_atol=model.residual_tolerance(fem_scene, contact.penalty * sizing.contact_size),
        couplings=contact.couplings(np.asarray(impact.direction), sizing.arc_half_angle),
        massless_surfaces=impact.surface_mass == "redistributed", material=material,
        step_loss=impact.energy_tolerance * scene.dt / estimate.duration
        if impact.adaptive_steps else None)
    return stepper, el, contact, sizing


def run(scene_path, out, scene: ImpactScene | None = None, comm=MPI.COMM_WORLD) -> int:
    """Integrate and write DIR (the scene read from scene_path unless given); 0 when the pin
    rebounded, 1 when the run stopped early."""
    if comm.size > 1:
        raise InputError("pinbore impact runs on one MPI rank (the rigid hub's reduction is "
                         "serial); run it without mpiexec")
    scene = scene or scenes.load(ImpactScene, scene_path)
    est = scene.estimate
    print(f"pinbore impact: {scene_path}: contact duration estimated on Liu's law "
          f"{est.duration:.3g} s (largest approach {est.max_approach:.3g} m); time step "
          f"{scene.dt:.3g} s, {est.duration / scene.dt:.0f} steps over the contact",
          file=sys.stderr)
    start = time.perf_counter()
    with atomic_directory(out, comm) as tmp:
        stepper, el, contact, sizing = build(scene, comm)
        setup = time.perf_counter() - start
        planned = int(np.ceil(stepper.t_end / scene.dt))
        with tqdm(total=planned, desc=f"impact {Path(scene_path).stem}", unit="step",
                  disable=None, leave=False) as bar:
            result = stepper.run(bar)
        solve = time.perf_counter() - start - setup
        summary = summarise(scene, scene_path, result, stepper, el, sizing, contact,
                            {"setup": setup, "solve": solve})
        rows = list(history_rows(result, stepper.impact_energy))
        impact_file.write_history(tmp / impact_file.HISTORY, rows)
        if scene.output.picture:
            figure(tmp / "force_time.png", result, scene, summary)
        summary.wall_time_s["total"] = time.perf_counter() - start
        reasons = impact_file.verdict(summary) if result.stop is None else []
        if reasons:
            summary = summary.model_copy(update={"status": "suspect", "verdict": reasons})
        impact_file.write_summary(tmp / impact_file.SUMMARY, summary)
    if reasons:
        print(f"pinbore impact: {scene_path}: suspect: {'; '.join(reasons)}; wrote {out} "
              "(status suspect)", file=sys.stderr)
        return 1
    if result.stop is not None:
        print(f"pinbore impact: {scene_path}: stopped early: {result.stop}; kept "
              f"{len(result.records)} time points in {out} (marked incomplete)", file=sys.stderr)
        return 1
    return 0


def history_rows(result, impact_energy):
    for r in result.records:
        yield {"time": r.time, "approach": r.approach, "force": r.force,
               "hub_velocity": r.hub_velocity, "pin_velocity": r.pin_velocity,
               "half_angle": np.degrees(r.half_angle), "min_gap": r.min_gap,
               "kinetic": r.kinetic, "strain": r.strain, "plastic_work": r.plastic_work,
               "contact_energy": r.contact_energy, "contact_work": r.contact_work,
               "friction_work": r.friction_work,
               "residual": book_residual(impact_energy, r),
               "newton_iterations": r.newton_iterations, "time_step": r.time_step}


def book_residual(impact_energy: float, r) -> float:
    """E_0 - K - U - W_p - Pi_c - W_f (J/m): what the energy book misses at the record r."""
    return (impact_energy - r.kinetic - r.strain - r.plastic_work - r.contact_energy
            - r.friction_work)


def contact_window(records) -> tuple[float, float] | None:
    """(first touch, separation) in s: the step ends where the smallest gap changes sign,
    placed by linear interpolation; None without a contact that ended."""
    t = np.array([r.time for r in records])
    g = np.array([r.min_gap for r in records])
    force = np.array([r.force for r in records])
    loaded = np.flatnonzero(force > 0)
    if loaded.size == 0 or loaded[-1] + 1 >= len(records):
        return None

    def crossing(i, j):   # between records i and j, g from one sign to the other
        if g[i] == g[j]:
            return t[j]
        return t[i] + (t[j] - t[i]) * g[i] / (g[i] - g[j])
    first, last = loaded[0], loaded[-1]
    on = crossing(first - 1, first) if first > 0 and g[first - 1] > 0 >= g[first] else t[first]
    off = crossing(last, last + 1) if g[last] <= 0 < g[last + 1] else t[last + 1]
    return float(on), float(off)


def summarise(scene, scene_path, result, stepper, el, sizing, contact, wall):
    records = result.records
    e0 = stepper.impact_energy
    last = records[-1]
    d = np.asarray(scene.impact.direction)
    window = contact_window(records)
    separated = result.stop is None and window is not None
    p = result.momentum
    rebound = float(p @ p) / (2 * stepper.mass)
    peak = max(records, key=lambda r: r.force)
    residuals = [abs(book_residual(e0, r)) / e0 for r in records]
    book = impact_file.EnergyBook(
        impact_J_per_m=e0, kinetic_J_per_m=last.kinetic, strain_J_per_m=last.strain,
        plastic_J_per_m=last.plastic_work,
        contact_J_per_m=last.contact_energy, contact_work_J_per_m=last.contact_work,
        friction_J_per_m=last.friction_work,
        rebound_J_per_m=rebound, wave_J_per_m=last.kinetic + last.strain - rebound,
        residual_J_per_m=book_residual(e0, last),
        scheme_residual_J_per_m=e0 - last.kinetic - last.strain - last.plastic_work - last.contact_work,
        max_relative_residual=max(residuals))
    est = scene.estimate
    return impact_file.ImpactSummary(
        scene_file=str(scene_path), scene=scene.model_dump(),
        status="complete" if result.stop is None else "incomplete", stop=result.stop,
        speed_m_per_s=scene.impact.speed, pin_mass_kg_per_m=stepper.mass,
        hub_mass_kg_per_m=stepper.hub_mass,
        restitution=float(-(p @ d) / (stepper.mass * scene.impact.speed)) if separated else None,
        rebound_velocity_m_per_s=list(p / stepper.mass),
        contact_duration_s=window[1] - window[0] if separated else None,
        peak_force_N_per_m=peak.force, approach_at_peak_m=peak.approach,
        max_approach_m=max(r.approach for r in records), energy=book,
        max_plastic_strain=last.max_plastic_strain,
        estimate={"law": "liu", "contact_duration_s": est.duration,
                  "max_approach_m": est.max_approach},
        time_step_s=scene.dt, spectral_radius=scene.impact.spectral_radius,
        steps=len(records) - 1, steps_in_contact=result.steps_in_contact,
        cutbacks=result.cutbacks, energy_rejections=result.energy_rejections,
        smallest_step_s=min(r.time_step for r in records[1:]) if len(records) > 1 else None,
        newton_iterations=sum(r.newton_iterations for r in records),
        factorizations=result.factorizations,
        dofs=el.num_dofs,
        mesh={"contact_size_m": sizing.contact_size,
              "cells": el.mesh.topology.index_map(2).size_global,
              "pin_surface_nodes": len(contact.pin_X)},
        contact={"method": scene.contact.method, "penalty_Pa_per_m": contact.penalty,
                 "gap_tolerance_m": stepper.gap_tolerance
                 if scene.contact.method == "augmented-lagrangian" else None,
                 "friction": scene.contact.friction},
        wall_time_s=dict(wall), platform={"python": platform.python_version(),
                                          "machine": platform.machine()})


def figure(path, result, scene, summary) -> None:
    """Contact force and approach against time, and the energy book."""
    r = result.records
    t = np.array([x.time for x in r]) * 1e6
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 4.8))
    ax.plot(t, [x.force / 1e3 for x in r], "C0", lw=1.2)
    ax.set_xlabel("time (us)")
    ax.set_ylabel("contact force (kN/m)", color="C0")
    twin = ax.twinx()
    twin.plot(t, [x.approach * 1e6 for x in r], "C1", lw=1)
    twin.set_ylabel("approach (um)", color="C1")
    e = summary.restitution
    ax.set_title(f"impact at {scene.impact.speed:g} m/s: peak {summary.peak_force_N_per_m / 1e3:.4g} kN/m, "
                 f"e = {'-' if e is None else f'{e:.4f}'}")
    ax.grid(alpha=0.3)
    e0 = summary.energy.impact_J_per_m
    for name, values in (("kinetic", [x.kinetic for x in r]), ("strain", [x.strain for x in r]),
                         ("plastic work", [x.plastic_work for x in r]),
                         ("contact (penalty)", [x.contact_energy for x in r]),
                         ("friction work", [x.friction_work for x in r]),
                         ("residual", [book_residual(e0, x) for x in r])):
        bx.plot(t, np.asarray(values) / e0, label=name, lw=1)
    bx.set_xlabel("time (us)")
    bx.set_ylabel("energy / impact energy")
    bx.set_title("energy book")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8)
    save_png(fig, path, layout=True)
