"""A body's FE model reduced to a flexible body (fem.modes): frequencies against the
Euler-Bernoulli beam [Blevins1979] and the cantilevered plate [Leissa1969], the eigenvalues'
convergence at the element's order, the floating frame's invariants against the rigid body's
closed forms, the geometric stiffening against the Southwell coefficient of the exact beam
mode, the reduction's convergence with the modes it keeps, the reduced body's file and the
command's bad input.
"""

import copy
import math

import numpy as np
import pytest
from conftest import pinbore

from pinbore.core.errors import InputError
from pinbore.fem.modes import file as body_file
from pinbore.fem.modes import reduction
from pinbore.fem.modes.scene import ModesScene

STEEL = {"E": 2.1e11, "nu": 0.3, "density": 7850.0}
CLAMPED_FREE = np.array([1.87510407, 4.69409113, 7.85475744])    # beta_n L [Blevins1979]
FREE_FREE = np.array([4.73004074, 7.85320462, 10.9956078])


def bar(length=1.0, width=0.01, thickness=0.01, cell=0.005, dim=2, interfaces=("a",),
        fixed=6, modes=3, degree=2, full=0, **body):
    return ModesScene.model_validate({
        "body": {"shape": "bar", "dim": dim, "length": length, "width": width,
                 "thickness": thickness, "cell_size": cell, **body},
        "material": STEEL,
        "reduction": {"interfaces": list(interfaces), "fixed_interface_modes": fixed,
                      "modes": modes, "degree": degree, "full_modes": full}})


def beam_omega(beta_l, scene) -> np.ndarray:
    """Euler-Bernoulli: omega_n = (beta_n L)^2 sqrt(E I / (rho A L^4)), bending about z (the
    width w along y: I = t w^3 / 12)."""
    b = scene.body
    EI = scene.material.E * b.thickness * b.width ** 3 / 12
    rhoA = scene.material.density * b.thickness * b.width
    return beta_l ** 2 * np.sqrt(EI / (rhoA * b.length ** 4))


def timoshenko_bound(beta_l, scene) -> np.ndarray:
    """An upper bound of the relative shift of shear and rotary inertia below Euler-Bernoulli:
    the first-order shift is (beta r)^2 (1 + E / (kappa G)) / 2 times a factor of order one
    (r^2 = I / A = w^2 / 12, kappa = 5/6); twice that."""
    b, m = scene.body, scene.material
    r2 = b.width ** 2 / 12
    return (beta_l / b.length) ** 2 * r2 * (1 + 2 * (1 + m.nu) / (5 / 6))


@pytest.fixture(scope="module")
def cantilever():
    scene = bar()
    fe = reduction.FEBody(reduction.mesh_of(scene), scene)
    interior, TB = reduction.rigid_interfaces(fe, scene)
    fixed, _ = reduction.craig_bampton(fe, scene, interior, TB)
    return scene, fe, interior, fixed


def test_cantilevered_bar_matches_euler_bernoulli(cantilever):
    """The fixed-interface modes of a bar held at its end face (h / L = 1/100, plane stress,
    P2): the first three bending frequencies below Euler-Bernoulli's by less than the
    Timoshenko shift (2e-3 for the third) plus the mesh's error (2e-4)."""
    scene, _, _, fixed = cantilever
    omega = np.sqrt(fixed.values[:3])
    exact = beam_omega(CLAMPED_FREE, scene)
    shift = omega / exact - 1
    assert np.all(shift < 2e-4), shift
    assert np.all(-shift < timoshenko_bound(CLAMPED_FREE, scene) + 2e-4), shift


def test_free_bar_full_and_reduced_match_euler_bernoulli():
    """Free-free: the whole FE model's free modes (shift-invert below zero) and the reduced
    body's (two end interfaces, eight fixed-interface modes) against Euler-Bernoulli, and the
    reduced against the whole model within 1e-3 (the truncation)."""
    scene = bar(interfaces=("a", "b"), fixed=8, modes=3, full=3)
    reduced = reduction.reduce(scene)
    exact = beam_omega(FREE_FREE, scene)
    bound = timoshenko_bound(FREE_FREE, scene) + 2e-4
    for omega in (reduced.full_omega, reduced.omega):
        shift = omega / exact - 1
        assert np.all(shift < 2e-4) and np.all(-shift < bound), shift
    assert np.all(np.abs(reduced.omega / reduced.full_omega - 1) < 1e-3)


@pytest.mark.parametrize("degree, order", [(1, 2), (2, 4)])
def test_eigenvalues_converge_at_the_elements_order(degree, order):
    """The first free-free eigenvalue of a bar (h / L = 1/10: a smooth eigenfunction, no
    clamped corner) on meshes of h, h/2, h/4 against a P2 mesh of h/12: the error falls as
    h^(2p) (the eigenvalue of a Lagrange element of degree p). The meshes are unstructured:
    the observed orders, averaged over the two halvings, within 0.7 of 2p."""
    def eigenvalue(cell, p):
        scene = bar(width=0.1, cell=cell, degree=p)
        fe = reduction.FEBody(reduction.mesh_of(scene), scene)
        return reduction.free_modes(fe.K, fe.M, 1, 3, 1e5)[0] ** 2

    reference = eigenvalue(0.004, 2)
    errors = np.array([eigenvalue(cell, degree) - reference for cell in (0.05, 0.025, 0.0125)])
    assert np.all(errors > 0)   # a conforming Galerkin approximation is stiff
    observed = np.mean(np.log2(errors[:-1] / errors[1:]))
    assert abs(observed - order) < 0.7, (observed, errors)


def test_cantilevered_plate_matches_leissa():
    """A square aluminium plate (a = 0.5 m, h = 5 mm) held along one edge: the first four
    frequency parameters omega a^2 sqrt(rho h / D) against Leissa's 3.492, 8.525, 21.43,
    27.33 [Leissa1969] within 1 % (his values are Ritz solutions of about 0.1 %; the solid's
    shear and its clamped edge differ from Kirchhoff's by O((h/a)^2) = 1e-4; the P2 mesh
    of 25 mm measured 0.25 %)."""
    E, nu, rho, a, h = 7e10, 0.3, 2700.0, 0.5, 0.005
    scene = ModesScene.model_validate({
        "body": {"shape": "panel", "dim": 3, "length": a, "width": a, "thickness": h,
                 "cell_size": 0.025},
        "material": {"E": E, "nu": nu, "density": rho},
        "reduction": {"interfaces": ["edge"], "fixed_interface_modes": 4, "modes": 4}})
    fe = reduction.FEBody(reduction.mesh_of(scene), scene)
    interior, TB = reduction.rigid_interfaces(fe, scene)
    fixed, _ = reduction.craig_bampton(fe, scene, interior, TB)
    D = E * h ** 3 / (12 * (1 - nu ** 2))
    parameter = np.sqrt(fixed.values) * a ** 2 * np.sqrt(rho * h / D)
    assert np.allclose(parameter, [3.492, 8.525, 21.43, 27.33], rtol=1e-2), parameter


def test_invariants_are_the_rigid_bodys_and_the_frame_is_mean_axis():
    """A box 0.3 x 0.02 x 0.01 m (3D, P2, no eyes: the mesh is the box exactly): mass rho V,
    centre of mass, inertia tensor m (b^2 + c^2) / 12 ... from the products with M, to
    round-off; the modes M-normalised (sum_a S_aa = 1) and in the mean-axis frame
    (1^T M Psi = 0, x~^T M Psi = 0); each interface frame at its face's centre."""
    L, w, t = 0.3, 0.02, 0.01
    scene = bar(length=L, width=w, thickness=t, cell=0.01, dim=3, interfaces=("a", "b"),
                fixed=6, modes=4)
    r = reduction.reduce(scene)
    m = STEEL["density"] * L * w * t
    assert r.mass == pytest.approx(m, rel=1e-12)
    assert np.allclose(r.centre, [L / 2, 0, 0], atol=1e-14)
    J = np.trace(r.second_moments) * np.eye(3) - r.second_moments
    assert np.allclose(J, np.diag([m * (w ** 2 + t ** 2), m * (L ** 2 + t ** 2),
                                   m * (L ** 2 + w ** 2)]) / 12, rtol=1e-10, atol=1e-16)
    assert np.allclose(sum(r.S[a, a] for a in range(3)), np.eye(4), atol=1e-10)
    scale = np.sqrt(m) * L
    assert np.abs(r.translation_coupling).max() < 1e-10 * scale
    turning = np.stack([r.s[1, 2] - r.s[2, 1], r.s[2, 0] - r.s[0, 2], r.s[0, 1] - r.s[1, 0]])
    assert np.abs(turning).max() < 1e-10 * scale * L
    assert np.allclose(r.interface_centres, [[-L / 2, 0, 0], [L / 2, 0, 0]], atol=1e-14)


def test_geometric_stiffening_gives_the_southwell_coefficient(cantilever):
    """A cantilever turning about its root (z): the centrifugal tension stiffens its first
    bending mode by K_G,zz = K1 Omega^2 per unit modal mass. K1 from the exact clamped-free
    mode phi [Blevins1979]: K1 = int (L^2 - x^2) / 2 phi'^2 dx / int phi^2 dx (the first-order
    perturbation of omega^2 = omega_0^2 + K1 Omega^2), 1.1933; the FE within 1e-3."""
    scene, fe, interior, fixed = cantilever
    x = np.linspace(0.0, 1.0, 200_001)
    b = CLAMPED_FREE[0]
    sigma = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))
    phi = np.cosh(b * x) - np.cos(b * x) - sigma * (np.sinh(b * x) - np.sin(b * x))
    K1 = np.trapezoid((1 - x ** 2) / 2 * np.gradient(phi, x) ** 2, x) / np.trapezoid(phi ** 2, x)
    modes = np.zeros((fe.nodes * fe.dim, 1))
    modes[interior, 0] = fixed.vectors[:, 0]
    KG = reduction.geometric_stiffening(fe, fixed.ksp, interior, modes, np.zeros(3))
    assert KG[2, 2, 0, 0] == pytest.approx(K1, rel=1e-3)
    assert not np.any(KG[:2]) and not np.any(KG[2, :2])   # a plane body turns about z only


def test_reduction_converges_as_modes_are_kept():
    """The reduced body's first free frequencies approach the whole model's (its interfaces
    tied alike) from above as fixed-interface modes are kept (Rayleigh-Ritz: a larger basis
    lowers every eigenvalue)."""
    errors = []
    for fixed in (2, 4, 8):
        scene = bar(length=0.12, width=0.024, thickness=0.01, cell=0.002, eye_radius=0.0095,
                    interfaces=("a", "b"), fixed=fixed, modes=3, full=3)
        r = reduction.reduce(scene)
        errors.append(r.omega / r.full_omega - 1)
    errors = np.array(errors)
    assert np.all(errors > -1e-9)
    assert np.all(np.diff(errors, axis=0) < 0), errors
    assert errors[-1].max() < 5e-3


# ---- the reduced body's file, and bad input

@pytest.fixture(scope="module")
def written(tmp_path_factory):
    from pinbore.fem.modes import run as modes_run

    scene = bar(length=0.3, width=0.02, cell=0.01, interfaces=("a", "b"), modes=3)
    reduced = reduction.reduce(scene)
    folder = tmp_path_factory.mktemp("body")
    source = folder / "scene.toml"
    source.write_text("# a scene\n")
    body = modes_run.body_of(reduced, source)
    body_file.write(folder / body_file.BODY, body)
    return folder / body_file.BODY, reduced


def test_body_file_round_trip(written):
    path, reduced = written
    body = body_file.read(path)
    assert np.array_equal(body.omega, reduced.omega) and np.array_equal(body.S, reduced.S)
    assert body.interfaces == ("a", "b") and body.interface("b") == 1
    assert np.allclose(body.inertia, np.trace(reduced.second_moments) * np.eye(3)
                       - reduced.second_moments)


def _rewrite(path, target, **changes):
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays.update(changes)
    np.savez(target, **arrays)
    return target


@pytest.mark.parametrize("changes, message", [
    ({"version": 0}, "version: 0 is not this pinbore's 1"),
    ({"format": "something else"}, "format: not a reduced body"),
    ({"omega": np.array([3.0, 2.0, 1.0])}, "omega: the frequencies must be positive and ascending"),
    ({"psi": np.zeros((4, 3, 3))}, "psi: shape (4, 3, 3)"),
    ({"mass": np.nan}, "mass: must be a positive, finite number"),
    ({"nodes": None}, "psi: shape"),   # a node fewer
    ({"dim": np.array([2, 2])}, "dim: not a single number"),
    ({"version": "x"}, "version: x is not this pinbore's 1"),
    ({"interfaces": np.array("a")}, "interfaces: not a list of names"),
    ({"second_moments": -np.eye(3)}, "second_moments: not symmetric positive semi-definite"),
    ({"translation_coupling": np.full((3, 3), 5.0)}, "translation_coupling: the modes move"),
    ({"cells": None}, "cells: not node indices"),   # as floats
])
def test_body_file_that_does_not_fit_is_one_line(written, tmp_path, changes, message):
    path, _ = written
    if changes.get("nodes", 1) is None:
        with np.load(path) as data:
            nodes = data["nodes"].copy()
        changes = {"nodes": nodes[:-1]}
    if changes.get("cells", 1) is None:
        with np.load(path) as data:
            changes = {"cells": data["cells"].astype(float)}
    target = _rewrite(path, tmp_path / "body.npz", **changes)
    with pytest.raises(InputError, match=None) as err:
        body_file.read(target)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_body_file_of_another_mesh_is_refused(written, tmp_path):
    path, _ = written
    with np.load(path) as data:
        nodes = data["nodes"] * 1.001
    with pytest.raises(InputError, match="mesh_sha256"):
        body_file.read(_rewrite(path, tmp_path / "body.npz", nodes=nodes))
    (tmp_path / "junk.npz").write_text("not a zip")
    with pytest.raises(InputError, match="not a reduced body"):
        body_file.read(tmp_path / "junk.npz")
    with pytest.raises(InputError, match="no such reduced body"):
        body_file.read(tmp_path / "missing.npz")


MODES = {"body": {"shape": "bar", "dim": 2, "length": 0.12, "width": 0.024, "thickness": 0.01,
                  "eye_radius": 0.0095, "cell_size": 0.002},
         "material": STEEL,
         "reduction": {"interfaces": ["a", "b"], "fixed_interface_modes": 4, "modes": 3}}


PANEL = {"body": {"shape": "panel", "dim": 3, "length": 0.2, "width": 0.1, "thickness": 2e-3,
                  "lugs": [0.05], "lug_radius": 0.008, "lug_bore_radius": 0.004, "lug_width": 0.02,
                  "cell_size": 0.02},
         "material": {"E": 7.0e10, "nu": 0.33, "density": 2700.0},
         "reduction": {"interfaces": ["lug1"], "fixed_interface_modes": 4, "modes": 2}}


def panel_with(**values):
    """A panel on one hinge lug with body keys changed (None: left out)."""
    data = copy.deepcopy(PANEL)
    data["body"].update(values)
    data["body"] = {k: v for k, v in data["body"].items() if v is not None}
    return data


def modes_with(table, **values):
    data = copy.deepcopy(MODES)
    data[table].update(values)
    return data


@pytest.mark.parametrize("scene, message", [
    (modes_with("reduction", modes=8), "reduction.modes: 8 is more than the reduced body can give (7"),
    (modes_with("reduction", interfaces=["a", "c"]), "reduction.interfaces.1: 'c' is not an interface"),
    (modes_with("reduction", interfaces=[]), "reduction.interfaces: List should have at least 1 item"),
    (modes_with("material", nu=0.5), "material.nu: Input should be less than 0.5"),
    (modes_with("body", eye_radius=0.012), "body: eye_radius must be smaller than width / 2"),
    (modes_with("body", shape="panel"), "body: a panel is a 3D solid: dim = 3"),
    (modes_with("body", lugs=[0.1]), "body: lugs belongs to a panel"),
    (modes_with("body", cell_size=0.1), "body: cell_size must be at most half"),
    (modes_with("reduction", degree=3), "reduction.degree: Input should be 1 or 2"),
    (modes_with("body", density=1.0), "body.density: unknown key"),
    (modes_with("reduction", interfaces=["a", "a"]), "reduction.interfaces: an interface is named twice"),
    (modes_with("reduction", stiffening_held=["c"]), "reduction.stiffening_held.0: 'c' is not one of"),
    (modes_with("reduction", stiffening_held=[]), "reduction.stiffening_held: one interface or more"),
    (panel_with(eye_radius=0.004), "body: eye_radius belongs to a bar"),
    (panel_with(lug_radius=None), "body: lugs need lug_radius"),
    (panel_with(lug_bore_radius=0.008), "body: lug_bore_radius must be smaller than lug_radius"),
    (panel_with(lug_radius=0.0009, lug_bore_radius=0.0005), "body: lug_radius must exceed thickness / 2"),
    (panel_with(lugs=[0.095]), "must lie on the edge"),
    (panel_with(lugs=[0.04, 0.05]), "body: the lugs overlap"),
    (panel_with(thickness=math.inf), "body.thickness: Input should be a finite number"),
])
def test_bad_modes_scene_is_one_line(write_scene, tmp_path, scene, message):
    from test_bad_input import expect_one_line

    out = tmp_path / "out"
    expect_one_line(pinbore("modes", write_scene(scene), "--out", out), message, out)


def test_the_stiffening_load_is_carried_by_the_held_interfaces_only():
    """A bar with two end interfaces turning about its end "a": held at "a" alone (the
    default) its axial stress is the cantilever's tension N(x) = rho A w^2 (L^2 - x^2) / 2, the
    bending stiffening of its first mode that of a cantilever's (positive); held at both ends
    the same load puts the outer part in compression (N(x) = rho A w^2 (L^2/6 - x^2/2)). The
    two differ, and the first interface alone is what a link turning about its root carries."""
    alone = reduction.reduce(bar(length=0.3, width=0.02, cell=0.005, interfaces=("a", "b"),
                                 fixed=6, modes=3))
    both = reduction.reduce(ModesScene.model_validate(
        bar(length=0.3, width=0.02, cell=0.005, interfaces=("a", "b"), fixed=6, modes=3)
        .model_dump() | {"reduction": {"interfaces": ["a", "b"], "fixed_interface_modes": 6,
                                       "modes": 3, "stiffening_held": ["a", "b"]}}))
    first_bending = 0
    assert alone.stiffening[2, 2, first_bending, first_bending] > 0
    assert alone.stiffening[2, 2, 0, 0] > 2 * abs(both.stiffening[2, 2, 0, 0])
