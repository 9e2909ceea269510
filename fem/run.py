"""`pinbore fem SCENE --out DIR`: solve a 2D or 3D pin-in-bore scene and write its results."""

import math
import platform
import sys
import time
from pathlib import Path

import dolfinx_solver  # noqa: F401  (must precede dolfinx)
from mpi4py import MPI
from tqdm import tqdm

from pinbore.core import scene as scenes
from pinbore.core.output import atomic_directory
from pinbore.fem import compliance, model, outputs
from pinbore.fem.scene import FemScene, worn_joint


def run(scene_path, out, comm=MPI.COMM_WORLD, scene: FemScene | None = None) -> int:
    """Solve and write DIR; 0 when every step converged, 1 when the run stopped early.
    `scene`: the scene file's model when the caller validated it already."""
    scene = scenes.load(FemScene, scene_path) if scene is None else scene
    start = time.perf_counter()
    worn = worn_joint(scene, Path(scene_path).parent, str(scene_path))
    with atomic_directory(out, comm) as tmp:
        stepper, el, contact, sizing, data = model.build(scene, comm, worn)
        setup = time.perf_counter() - start
        programme = scene.load.programme
        fields = (outputs.FieldWriter(tmp / "fields.xdmf", el, contact, stepper.material)
                  if scene.output.fields else None)
        # a progress bar on rank 0 when it writes to a terminal (tqdm decides: disable=None)
        with tqdm(total=scene.load.step_count, desc=f"fem {Path(scene_path).stem}", unit="step",
                  disable=None if comm.rank == 0 else True, leave=False) as bar:
            result = stepper.run(programme, bar, on_step=fields.write if fields else None)
        if fields:
            fields.close()
        # collective: every rank asks, rank 0 writes it
        beyond = stepper.material.plastic and stepper.material.beyond_table()
        solve = time.perf_counter() - start - setup
        if result.steps and scene.output.picture:
            if scene.geometry.dim == 2:
                outputs.picture(tmp / "contact.png", el, stepper.x, result, scene,
                                sizing.arc_half_angle, stepper.clearance)
            elif comm.rank == 0:
                outputs.pressure_pictures(tmp, result, scene, contact, el.symmetric)
        if comm.rank == 0:
            direction = scene.load.direction_deg
            outputs.write_curve(tmp / "curve.csv", result, direction, contact,
                                scene.tilt_pivot[2], 2 if el.symmetric else 1)
            outputs.write_pressure(tmp / "pressure.csv", result, direction, sizing.arc_half_angle,
                                   contact)
        if scene.output.compliance:
            # collective: the bodies' surface compliance (a conformal contact's kernel)
            kernel = compliance.surface_compliance(el, data.facet_tags, scene.geometry.pin_radius,
                                                   scene.geometry.bore_radius, scene.load.direction_deg)
            if comm.rank == 0:
                compliance.write(tmp / "compliance.csv", kernel)
        if comm.rank == 0:
            outputs.write_result(tmp / "result.json", summary(
                scene, scene_path, result, el, contact, stepper, sizing, comm, worn,
                {"setup": setup, "solve": solve,
                 "post": time.perf_counter() - start - setup - solve,   # pictures, files
                 "total": time.perf_counter() - start}, beyond))
    if beyond and comm.rank == 0:
        print(f"pinbore fem: {scene_path}: warning: the equivalent plastic strain went past the "
              "last pair of a hardening table (the yield stress was held constant there)",
              file=sys.stderr)
    if result.stop is not None:
        if comm.rank == 0:
            print(f"pinbore fem: {scene_path}: stopped early: {result.stop.message}; "
                  f"kept {len(result.steps)} converged steps in {out} (marked incomplete)",
                  file=sys.stderr)
        return 1
    return 0


def symmetry_note(scene, el) -> str | None:
    """What result.json says about the model's extent (3D)."""
    if scene.geometry.dim == 2:
        return None
    if el.symmetric:
        return ("half model z <= length/2, u_z = 0 on the mid-plane; forces, torque and work "
                "are those of the whole pin, pressure.csv covers the modelled half")
    why = ("tilted pin" if scene.geometry.tilt_deg else
           "tilt load" if scene.load.tilt_deg is not None else "mesh.symmetry = false")
    return f"full model ({why})"


def worn_note(worn, stepper) -> dict | None:
    """What result.json says about a worn joint: its deepest wear, the radii of the round
    joint its mesh was built on, where the worn pin first touches its bore."""
    if worn is None:
        return None
    return {"bore_max_depth_m": float(worn.bore_depth.max()),
            "pin_max_depth_m": float(worn.pin_depth.max()),
            "base_bore_radius_m": worn.bore_base, "base_pin_radius_m": worn.pin_base,
            "first_touch_m": stepper.clearance}


def summary(scene, scene_path, result, el, contact, stepper, sizing, comm, worn, wall,
            beyond=False):
    steps = result.steps
    return {
        "scene_file": str(scene_path),
        "scene": scene.model_dump(),
        "status": "complete" if result.stop is None else "incomplete",
        "stop": None if result.stop is None else {"approach_m": result.stop.approach,
                                                  "message": result.stop.message},
        "dofs": el.num_dofs,
        "worn": worn_note(worn, stepper),
        "ranks": comm.size,
        "mesh": {"contact_size_m": sizing.contact_size,
                 "refined_arc_half_angle_deg": math.degrees(sizing.arc_half_angle),
                 "cells": el.mesh.topology.index_map(scene.geometry.dim).size_global,
                 "pin_surface_nodes": len(contact.pin_X),
                 "symmetry": symmetry_note(scene, el)},
        "contact": {"method": scene.contact.method, "penalty_Pa_per_m": contact.penalty,
                    "gap_tolerance_m": stepper.gap_tolerance
                    if scene.contact.method == "augmented-lagrangian" else None,
                    "friction": scene.contact.friction,
                    "friction_terms_assembled": contact.friction is not None},
        "steps_converged": len(steps),
        "cutbacks": result.cutbacks,
        "newton_iterations": [s.newton_iterations for s in steps],
        "uzawa_iterations": [s.uzawa_iterations for s in steps],
        "factorizations": [s.factorizations for s in steps],
        "snes_reasons": [s.reasons for s in steps],
        "gap_violation_m": [s.gap_violation for s in steps],
        "plasticity": None if not stepper.material.plastic else {
            "plastic_work": sum(s.plastic_work for s in steps),     # J/m (3D: J)
            "max_plastic_strain": max((s.max_plastic_strain for s in steps), default=0.0),
            "beyond_hardening_table": beyond},
        "residual_approach_m": [s.residual_approach for s in steps
                                if math.isfinite(s.residual_approach)],
        "max_gap_violation_m": max((s.gap_violation for s in steps), default=None),
        "wall_time_s": wall,
        "step_wall_time_s": [s.wall_time for s in steps],
        "platform": {"python": platform.python_version(), "machine": platform.machine()},
    }
