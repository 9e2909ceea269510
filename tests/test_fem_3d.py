"""3D pin-in-bore contact against independent references: plane strain far from the ends,
the mirror image of a half model, edge loading at the bore's ends (lug), tilt, and Coulomb's
full-slip torque."""

import numpy as np
import pytest
from conftest import Solved, scene_dict

from pinbore.fem.contact import STICK, tributary_lengths

COARSE = {"contact_size": 5e-4, "grading": 0.5}


def line_load(solved, step, level):
    """Pressure resultant along the load per unit length (N/m) on one level of the pin."""
    angles, _ = solved.contact.pin_grid
    nodes = slice(level * angles.size, (level + 1) * angles.size)
    ring = tributary_lengths(solved.contact.pin_reference[nodes, :2])
    along = np.cos(step.contact.angle[nodes] - np.radians(solved.scene.load.direction_deg))
    return float(np.sum(ring * step.contact.pressure[nodes] * along))


def peak_by_level(solved, step):
    """Largest nodal pressure (Pa) on each level of the pin, and the levels z (m)."""
    angles, levels = solved.contact.pin_grid
    return step.contact.pressure.reshape(levels.size, angles.size).max(axis=1), levels


def three_d(length, mesh=None, load=None, **geometry):
    return scene_dict(geometry={"dim": 3, "length": length} | geometry,
                      mesh=COARSE | (mesh or {}), load={"steps": 1} | (load or {}))


def test_long_pin_carries_the_plane_strain_load_at_mid_length():
    """L = 10 R, no tilt: the line load at mid-length is the 2D plane-strain force per length
    on the same section mesh within 5 % (free ends relax the axial stress of plane strain:
    measured 2.7 % below)."""
    plane = Solved(scene_dict(mesh=COARSE, load={"steps": 1}))
    long = Solved(three_d(0.1, mesh={"layers": 12}))
    assert long.el.symmetric
    mid = np.argmin(np.abs(long.contact.pin_grid[1] - 0.05))
    ratio = line_load(long, long.run.steps[-1], mid) / plane.run.steps[-1].force[0]
    assert ratio == pytest.approx(1.0, abs=0.05)


def test_long_pin_carries_the_plane_strain_curve_times_its_length():
    """L = 10 R in a housing of 3 R (the pin long against its housing, so the housing's
    middle is in plane strain), no tilt: the whole pin's force is the 2D force per length
    on the same section mesh times L within the FE discretisation error, 3 % (the free ends
    relax the plane-strain axial stress over about a radius at each end: measured 2.1-2.3 %
    below, here at 5 and 10 um and at c = 30 um from 2 to 10 um)."""
    housing = {"housing_radius": 0.03}
    plane = Solved(scene_dict(geometry=housing, mesh=COARSE, load={"steps": 2}))
    long = Solved(three_d(0.1, mesh={"layers": 12}, load={"steps": 2}, **housing))
    for flat, whole in zip(plane.run.steps, long.run.steps):
        assert whole.force[0] / (flat.force[0] * 0.1) == pytest.approx(1.0, abs=0.03)


def test_half_model_is_the_mirror_image_of_the_full_one():
    """No tilt: the half model (mid-plane u_z = 0) has the nodes of the full one below the
    mid-plane and gives its force within 1e-3 (measured 1.7e-4) and its peak pressure on
    every level within 2 % (1.1 %). They differ only by the tetrahedra: gmsh splits the
    extruded prisms by node numbers, so the full mesh is not its own mirror image (its
    pressures are mirror-symmetric within 5 %: 3.4 % on this coarse mesh)."""
    half = Solved(three_d(0.02, mesh={"layers": 4}))
    full = Solved(three_d(0.02, mesh={"layers": 8, "symmetry": False}))
    assert half.el.symmetric and not full.el.symmetric
    assert half.run.steps[-1].force[0] == pytest.approx(full.run.steps[-1].force[0], rel=1e-3)
    p_half, z_half = peak_by_level(half, half.run.steps[-1])
    p_full, z_full = peak_by_level(full, full.run.steps[-1])
    np.testing.assert_allclose(z_full[:z_half.size], z_half, atol=1e-12)
    np.testing.assert_allclose(p_full[:p_half.size], p_half, atol=0.02 * p_full.max())
    np.testing.assert_allclose(p_full, p_full[::-1], atol=0.05 * p_full.max())


def test_pin_through_a_lug_loads_the_bore_edges_and_a_relief_unloads_them():
    """A pin running 5 mm beyond each end of a 20 mm bore: the bore's edge acts like the edge
    of a flat punch on the pin (a stiff corner on an elastic body that continues past it) and
    the pressure peaks just inside it, above the mid-length pressure by > 20 % (measured 38 %).
    An edge relief (circular, 2 mm long, 3 um deep) leaves the edge itself unloaded."""
    lug = Solved(three_d(0.02, mesh={"layers": 8}, pin_overhang=5e-3))
    peak, z = peak_by_level(lug, lug.run.steps[-1])
    near_edge = (z >= 0) & (z <= 1e-3)
    assert peak[near_edge].max() > 1.2 * peak[-1]
    assert np.all(peak[z < 0] == 0)   # no contact beyond the bore
    relieved = Solved(three_d(0.02, mesh={"layers": 8}, pin_overhang=5e-3,
                              relief_length=2e-3, relief_depth=3e-6))
    peak, z = peak_by_level(relieved, relieved.run.steps[-1])
    assert np.all(peak[z <= 2e-4] == 0)


def test_tilt_moves_the_pressure_to_one_end():
    """A pin tilted by 0.02 deg (its ends 3.5 um off the bore's axis): the full model is
    used, the pin touches before the clearance is crossed, and the pressure rises towards the
    end that leans into the load, carrying less than a third of it at the other end."""
    tilted = Solved(three_d(0.02, mesh={"layers": 8}, tilt_deg=0.02))
    assert not tilted.el.symmetric
    touch = 0.01 * np.sin(np.radians(0.02))
    assert tilted.stepper.clearance == pytest.approx(1e-5 - touch, rel=0.02)
    peak, z = peak_by_level(tilted, tilted.run.steps[-1])
    assert z[np.argmax(peak)] > 0.015
    assert peak[z < 0.005].max() < peak.max() / 3


def test_full_slip_torque_in_3d_is_coulomb():
    """mu = 0.2, the hub turned until the whole contact slips: the friction torque is
    mu R int p dA over the pin's surface (within 0.2 %), a half model counting twice."""
    mu = 0.2
    solved = Solved(three_d(0.02, mesh={"layers": 4}, load={"steps": 2, "rotation_deg": 0.1,
                                                             "slide_steps": 4},
                            ) | {"contact": {"method": "augmented-lagrangian", "friction": mu}})
    last = solved.run.steps[-1]
    assert not np.any(last.contact.status == STICK)
    coulomb = 2 * mu * 9.99e-3 * np.sum(solved.contact.weights * last.contact.pressure)
    assert last.torque == pytest.approx(coulomb, rel=2e-3)


def test_kept_factors_change_the_cost_not_the_solution(monkeypatch):
    """GMRES on the factors of an earlier Jacobian (fem.solver.KeptLU) against Newton with a
    fresh LU of every Jacobian: the same Newton iterations and forces. Each linear solve
    reaches 1e-8 of its residual, so the Newton iterates agree far below the 1e-7 asked."""
    from pinbore.fem import solver

    data = {"kind": "fem",
            "geometry": {"dim": 3, "pin_radius": 9.99e-3, "bore_radius": 10.0e-3,
                         "housing_radius": 0.2, "hub_radius": 2.0e-3, "length": 0.02},
            "materials": {"pin": {"E": 210e9, "nu": 0.3}, "bore": {"E": 210e9, "nu": 0.3}},
            "contact": {"method": "augmented-lagrangian", "friction": 0.0},
            "load": {"max_approach": 1.0e-5, "steps": 3, "direction_deg": -90.0},
            "mesh": {"contact_size": 6e-4, "grading": 0.5, "layers": 4}}
    kept = Solved(data)
    monkeypatch.setattr(solver, "MIN_WORTH", -1)
    monkeypatch.setattr(solver.KeptLU, "worth_iterations", lambda self: -1.0)
    fresh = Solved(data)
    assert sum(s.factorizations for s in fresh.run.steps) == sum(s.newton_iterations
                                                                  for s in fresh.run.steps)
    assert sum(s.factorizations for s in kept.run.steps) < sum(s.factorizations
                                                                for s in fresh.run.steps)
    assert [s.newton_iterations for s in kept.run.steps] == [s.newton_iterations
                                                              for s in fresh.run.steps]
    np.testing.assert_allclose(kept.forces, fresh.forces, rtol=1e-7)
