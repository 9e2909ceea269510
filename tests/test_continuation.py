"""Continuation of periodic motions, their Floquet multipliers and bifurcations, against
closed forms and an independent integration: the forced linear oscillator (amplitude, phase
and multipliers in closed form), the hardening Duffing oscillator (its folds against the
one-harmonic balance, and the jumps of direct up- and down-sweeps there), and the impact
oscillator of the shipped scene (grazing where the linear response reaches the gap, and
the multipliers of an impacting orbit against a separate integration with located
onsets)."""

import math
import tomllib

import numpy as np
import pytest
from conftest import ROOT
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

from pinbore.reduced.dynamics import continuation as method

IMPACT = ROOT / "scenes" / "reduced" / "impact_oscillator.toml"


# ---- the bifurcations' normal forms, as period maps with known points
class NormalForm:
    """A family given by its period map directly: the normal form of a bifurcation at p = 0
    (x a vector), so that each test function is checked where it must vanish."""

    tolerance = 1e-12

    def __init__(self, step):
        self.step = step

    def map(self, x, p, multiple):
        for _ in range(multiple):
            x = self.step(np.asarray(x, float), p)
        return x

    def measure(self, x, p, multiple):
        return {"amplitude": float(np.linalg.norm(x)), "gap": None}


def rotation(angle):
    return np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]])


NORMAL_FORMS = {
    # a saddle-node: x + p - x^2 has the fixed points x = +-sqrt(p), folding at p = 0
    "fold": (lambda x, p: np.array([x[0] + p - x[0] ** 2, 0.5 * x[1]]), np.array([0.5, 0.0]), 0.25, -0.2),
    # a pitchfork of the fixed point 0: x + p x - x^3, multiplier 1 + p passing +1 at p = 0
    "branch_point": (lambda x, p: np.array([x[0] + p * x[0] - x[0] ** 3 + 1e-3 * p, 0.5 * x[1]]),
                     np.array([0.0, 0.0]), -0.3, 0.3),
    # a flip: -(1 + p) x + x^3, multiplier -(1 + p) passing -1 at p = 0
    "period_doubling": (lambda x, p: np.array([-(1 + p) * x[0] + x[0] ** 3, 0.5 * x[1]]),
                        np.array([0.0, 0.0]), -0.3, 0.3),
    # a Neimark-Sacker: the pair (1 + p) exp(+-i 0.7) passing the unit circle at p = 0
    "neimark_sacker": (lambda x, p: (1 + p) * rotation(0.7) @ x - (x @ x) * x, np.array([0.0, 0.0]), -0.3, 0.3),
}


@pytest.mark.parametrize("kind", list(NORMAL_FORMS))
def test_each_bifurcation_is_found_where_its_normal_form_has_it(kind):
    """Continued through p = 0, each normal form's branch shows its bifurcation there and no
    other (located within 1e-5: the location's tolerance, 1e-6 of the range, and the
    difference step), with the multiplier it passes."""
    step, x, low, high = NORMAL_FORMS[kind]
    family = NormalForm(step)
    line = method.Continuation(family, min(low, high), max(low, high))
    start = line.first(x, low, 1.0 if high > low else -1.0)
    branch = line.run(start, 0.05, 200)
    found = [(s.kind, s.p) for s in branch.specials]
    assert [k for k, _ in found] == [kind], found
    assert found[0][1] == pytest.approx(0.0, abs=1e-5)


def test_two_doublings_within_one_step_are_both_found():
    """Two flips at p = 0 and p = 0.005, a tenth of the first step apart: the products of
    the multipliers' test functions do not change sign over a step holding both, so the
    step is retried shorter until each lies in its own: each found, within a hundredth of
    their distance (5e-5) of its value."""
    family = NormalForm(lambda x, p: np.array([-(1 + p) * x[0] + x[0] ** 3,
                                               -(1 + p - 0.005) * x[1] + x[1] ** 3]))
    line = method.Continuation(family, -0.3, 0.3)
    branch = line.run(line.first(np.zeros(2), -0.3, 1.0), 0.05, 200)
    found = [(s.kind, s.p) for s in branch.specials]
    assert [k for k, _ in found] == ["period_doubling"] * 2, found
    assert [p for _, p in found] == pytest.approx([0.0, 0.005], abs=5e-5)


def test_a_step_that_lands_on_a_bifurcation_reports_it():
    """A flip -(1 + p) x whose branch has a point exactly at p = 0, where the test function
    is 0: the step that reached it holds the doubling."""
    family = NormalForm(lambda x, p: np.array([-(1 + p) * x[0], 0.5 * x[1]]))
    line = method.Continuation(family, -0.5, 0.5)
    branch = line.run(line.first(np.zeros(2), -0.5, 1.0), 0.5, 10)
    assert any(pt.p == 0.0 for pt in branch.points)
    assert [(s.kind, s.p) for s in branch.specials] == [("period_doubling", 0.0)]


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_doubled_branch_of_a_sub_and_a_supercritical_flip(sign):
    """-(1 + p) x + s x^3 flips at p = 0; its 2-cycle is x^2 = s p: on the side where the
    fixed point is unstable (p > 0, supercritical, s = +1: the 2-cycle stable) or stable
    (p < 0, subcritical, s = -1: the 2-cycle unstable). The switch finds it either way."""
    family = NormalForm(lambda x, p: np.array([-(1 + p) * x[0] + sign * x[0] ** 3, 0.5 * x[1]]))
    line = method.Continuation(family, -0.3, 0.3)
    branch = line.run(line.first(np.zeros(2), -0.3, 1.0), 0.05, 200)
    (flip,) = [s for s in branch.specials if s.kind == "period_doubling"]
    doubled = line.doubled(flip, 0.05, 20)
    assert doubled is not None and doubled.multiple == 2
    for pt in doubled.points:
        assert sign * pt.p > 0 and pt.x[0] ** 2 == pytest.approx(sign * pt.p, rel=1e-6)
        assert pt.stable == (sign > 0)


class Grazing(NormalForm):
    """A normal form whose orbit grazes at p = 0 (its gap -p), where its multipliers jump
    as an impact's saltation makes them: the second from -0.5 to -1.5 (a flip that is the
    grazing's), and the first from 0.5 to 1 + (p - P_BRANCH), which passes +1 at
    P_BRANCH, a pitchfork of the orbit 0 just past the grazing."""

    def measure(self, x, p, multiple):
        return {"amplitude": float(np.linalg.norm(x)), "gap": -p}


P_BRANCH = 0.005


def grazing_map(x, p):
    if p <= 0:
        return np.array([0.5 * x[0], -0.5 * x[1]])
    return np.array([(1 + p - P_BRANCH) * x[0] - x[0] ** 3, -1.5 * x[1]])


def test_a_branch_point_just_past_a_grazing_is_found_and_the_grazings_jump_is_not():
    """The grazing at p = 0 and the branch point at p = 0.005 lie within one step (0.05): the
    step is cut around the grazing until the branch point lies in a piece of its own (found
    within 1e-5 of 0.005), while the flip of the multiplier that jumps at the grazing
    itself stays the grazing's."""
    line = method.Continuation(Grazing(grazing_map), -0.3, 0.3)
    branch = line.run(line.first(np.zeros(2), -0.3, 1.0), 0.05, 40)
    found = [(s.kind, s.p) for s in branch.specials]
    assert [k for k, _ in found] == ["grazing", "branch_point"], found
    assert found[0][1] == pytest.approx(0.0, abs=1e-5) and found[1][1] == pytest.approx(P_BRANCH, abs=1e-5)


def test_a_tangent_that_flips_without_a_multiplier_at_one_is_no_fold():
    """Two orbits whose multipliers stay inside the unit circle (det(P_x - I) keeps its sign)
    but whose tangents' q-components differ in sign (an orientation that flipped): no fold
    is reported, and the second tangent is turned to go on the way the first went."""
    line = method.Continuation(NormalForm(lambda x, p: 0.5 * x), 0.0, 1.0)
    mu = np.array([0.6 + 0.3j, 0.6 - 0.3j])
    a = method.Point(np.zeros(2), 0.4, np.array([0.1, 0.0, 0.99]), mu, {"gap": None})
    b = method.Point(np.zeros(2), 0.41, np.array([0.1, 0.0, -0.99]), mu, {"gap": None})
    assert line.specials(a, method.oriented(a, b), 0.01, 1) == []
    assert b.tangent[-1] > 0


def test_a_noisy_map_gets_the_difference_step_that_resolves_its_multipliers():
    """A linear map with multipliers -0.6 and 0.3 plus a deterministic noise of 3e-6 that
    varies on a scale of 1e-7 (an adaptive integration's error: its step sequence changes
    with the state). At FD_STEP the quotients carry noise of about 3e-6 / 1e-4 = 0.03 (the
    largest multiplier comes out 0.017 off); the step chosen at the first orbit is the
    smallest FD_STEP 2^k from which two doublings each move the largest multiplier by at
    most SPREAD_WARNING / 2, and there the multipliers are within SPREAD_WARNING of the
    exact ones (the noise falls as 1/h, and a linear map has no truncation)."""
    a = np.array([[-0.6, 0.0], [0.0, 0.3]])

    def noisy(x, p):
        return a @ x + p + 3e-6 * np.sin(1e7 * x + np.array([0.3, 1.1]) * np.sum(1e7 * x))

    line = method.Continuation(NormalForm(noisy), -1.0, 1.0)
    start = line.first(np.linalg.solve(np.eye(2) - a, np.zeros(2)), 0.0, 1.0)
    assert abs(np.max(np.abs(start.multipliers)) - 0.6) > method.SPREAD_WARNING   # noise at FD_STEP
    point, spread = line.resolve(start)
    assert line.step > method.FD_STEP and spread <= method.SPREAD_WARNING
    assert np.sort(point.multipliers.real) == pytest.approx([-0.6, 0.3], abs=method.SPREAD_WARNING)
    branch = line.run(point, 0.05, 4)   # the branch goes on at that step
    assert all(abs(np.max(np.abs(q.multipliers)) - 0.6) <= method.SPREAD_WARNING for q in branch.points)


def test_a_map_that_is_not_finite_is_a_failed_orbit():
    """An integration that returns NaN without raising is a FloatingPointError, which every
    caller takes as a failed orbit (a linear algebra error would escape them)."""
    family = NormalForm(lambda x, p: x * math.nan)
    with pytest.raises(FloatingPointError, match="not finite"):
        method.Continuation(family, 0.0, 1.0).first(np.ones(2), 0.5, 1.0)


# ---- the hardening Duffing oscillator x'' + 2 zeta x' + x + beta x^3 = F cos(w t)
ZETA, BETA, FORCE = 0.05, 0.1, 0.5


class Duffing:
    """A family for continuation in w (and a direct sweep's `settle`)."""

    tolerance = 1e-9

    @staticmethod
    def rhs(w):
        return lambda t, z: [z[1], -2 * ZETA * z[1] - z[0] - BETA * z[0] ** 3 + FORCE * math.cos(w * t)]

    def orbit(self, x, w, periods, samples=2):
        t = np.linspace(0, periods * 2 * math.pi / w, samples)
        return solve_ivp(self.rhs(w), (0, t[-1]), x, method="DOP853", rtol=1e-11, atol=1e-12, t_eval=t).y

    def map(self, x, w, multiple):
        return self.orbit(x, w, multiple)[:, -1]

    def measure(self, x, w, multiple):
        y = self.orbit(x, w, multiple, 401)[0]
        return {"amplitude": 0.5 * float(y.max() - y.min()), "gap": None}


def harmonic_balance_folds():
    """The folds of the one-harmonic response A^2 ((1 - w^2 + 3 beta A^2 / 4)^2 + (2 zeta w)^2)
    = F^2, where its derivative in A vanishes too: (w, A), lower then upper."""
    def equations(v):
        a, w = v
        s = 1 - w * w + 0.75 * BETA * a * a
        return [a * a * (s * s + (2 * ZETA * w) ** 2) - FORCE ** 2,
                2 * a * (s * s + (2 * ZETA * w) ** 2) + 3 * BETA * a ** 3 * s]
    return [tuple(fsolve(equations, guess)[::-1]) for guess in ([1.5, 1.2], [3.5, 1.4])]


def test_duffing_folds_against_the_harmonic_balance():
    """The continued response folds twice, at the one-harmonic balance's folds within the
    error of keeping one harmonic (beta A^2 = 1.3 at the upper fold: its third harmonic is
    not small there): measured 0.03 % (lower) and 0.23 % (upper) in frequency, 0.14 % and
    1.5 % in amplitude."""
    duffing = Duffing()
    line = method.Continuation(duffing, 1.0, 1.8)
    x = np.zeros(2)
    for _ in range(100):
        x = duffing.map(x, 1.0, 1)
    branch = line.run(line.first(x, 1.0, 1.0), 0.02, 120)
    folds = sorted((s for s in branch.specials if s.kind == "fold"), key=lambda s: s.p)
    assert [s.kind for s in branch.specials] == ["fold", "fold"]
    for fold, (w, a) in zip(folds, harmonic_balance_folds()):
        assert fold.p == pytest.approx(w, rel=3e-3)
        assert fold.point.measures["amplitude"] == pytest.approx(a, rel=2e-2)
    # the branch climbs the resonance to the upper fold, comes back along the middle branch,
    # unstable (a multiplier beyond +1), to the lower fold, and leaves along the lower one
    first, second = sorted(s.after for s in folds)
    assert all(not p.stable for p in branch.points[first:second])
    assert all(p.stable for p in branch.points[:first - 1] + branch.points[second + 1:])


class DoubleWell(Duffing):
    """The double-well Duffing x'' + 0.3 x' - x + x^3 = gamma cos 1.2 t of tests/test_dynamics.py
    (Jordan & Smith's set), continued in gamma."""

    @staticmethod
    def rhs(gamma):
        return lambda t, z: [z[1], -0.3 * z[1] + z[0] - z[0] ** 3 + gamma * math.cos(1.2 * t)]

    def orbit(self, x, gamma, periods, samples=2):
        t = np.linspace(0, periods * 2 * math.pi / 1.2, samples)
        return solve_ivp(self.rhs(gamma), (0, t[-1]), x, method="DOP853", rtol=1e-11, atol=1e-12, t_eval=t).y


@pytest.mark.slow
def test_period_doublings_by_continuation_agree_with_the_brute_force_attractors():
    """Continued in gamma, the period-1 orbit doubles at gamma_1 and the doubled branch,
    switched onto there, doubles again at gamma_2: the attractors found by brute force (a
    transient of 400 periods, then Poincare samples) are period 1 just below gamma_1 and
    period 2 just above, period 2 just below gamma_2 and period 4 just above (+-0.005, and
    +-0.0025 at gamma_2, where the cascade's next doubling follows within 0.005; nearer, the
    multiplier near -1 makes the transient slow); the doubled branch's orbit at
    gamma = 0.28 is one of the period-2 attractor's pair of points (1e-6)."""
    from pinbore.reduced.dynamics import flow

    well = DoubleWell()
    line = method.Continuation(well, 0.2, 0.3)
    x = np.array([1.0, 0.0])
    for _ in range(200):
        x = well.map(x, 0.2, 1)
    branch = line.run(line.first(x, 0.2, 1.0), 0.05, 60)
    first = [s for s in branch.specials if s.kind == "period_doubling"]
    assert len(first) == 1
    doubled = line.doubled(first[0], 0.05, 40)
    assert doubled is not None and doubled.multiple == 2
    second = [s for s in doubled.specials if s.kind == "period_doubling"]
    assert len(second) == 1
    gamma_1, gamma_2 = first[0].p, second[0].p
    assert 0.26 < gamma_1 < 0.27 < 0.28 < gamma_2 < 0.29   # tests/test_dynamics.py's attractors

    def attractor_period(gamma):
        state = np.array([1.0, 0.0])
        for _ in range(400):
            state = well.map(state, gamma, 1)
        samples = [state := well.map(state, gamma, 1) for _ in range(16)]
        return flow.period_of(np.array(samples), tol=1e-6), samples
    for gamma, period in ((gamma_1 - 0.005, 1), (gamma_1 + 0.005, 2), (gamma_2 - 0.0025, 2), (gamma_2 + 0.0025, 4)):
        assert attractor_period(gamma)[0] == period, gamma
    _, samples = attractor_period(0.28)
    on_branch = min(doubled.points, key=lambda p: abs(p.p - 0.28))
    doubled_line = method.Continuation(well, 0.2, 0.3, 2)
    orbit = doubled_line.first(on_branch.x, 0.28, 1.0).x
    assert min(np.linalg.norm(orbit - samples[-1]), np.linalg.norm(orbit - samples[-2])) < 1e-6


# ---- mechanisms
def family_of(data, parameter, value, tmp_path):
    from pinbore.reduced.dynamics import studies

    return studies.MechanismFamily(studies.SceneFile(tmp_path / "scene.toml", data), parameter, value)


def linear_oscillator(f_hz):
    """A 2 kg block on a prismatic guide along y, held by a spring k = 800 N/m and a damper
    c = 4 N s/m (w_n = 20 rad/s, zeta = 0.05), forced by 3 N cos(2 pi f t)."""
    return {"kind": "planar", "duration": 1.0,
            "bodies": [{"name": "block", "mass": 2.0, "inertia": 0.01}],
            "joints": [{"type": "prismatic", "body": "block", "axis_deg": 90.0}],
            "springs": [{"body_i": "ground", "point_i": [0.0, -1.0], "body_j": "block",
                         "point_j": [0.0, 0.0], "stiffness": 800.0, "damping": 4.0, "free_length": 1.0}],
            "loads": [{"body": "block", "force": [0.0, 3.0], "frequency_hz": f_hz}],
            "integrator": {"rtol": 1e-11, "atol": 1e-14, "max_step": 1e-3}}


def spatial_linear_oscillator(f_hz):
    """linear_oscillator in space: the guide a prismatic joint along y."""
    data = linear_oscillator(f_hz)
    data["kind"] = "spatial"
    data["bodies"][0]["inertia"] = np.diag([0.01, 0.01, 0.01]).tolist()
    data["joints"] = [{"type": "prismatic", "body_i": "ground", "point_i": [0.0, 0.0, 0.0], "axis_i": [0.0, 1.0, 0.0],
                       "body_j": "block", "point_j": [0.0, 0.0, 0.0], "axis_j": [0.0, 1.0, 0.0]}]
    data["springs"][0] |= {"point_i": [0.0, -1.0, 0.0], "point_j": [0.0, 0.0, 0.0]}
    data["loads"][0]["force"] = [0.0, 3.0, 0.0]
    return data


@pytest.mark.parametrize("scene", [linear_oscillator, spatial_linear_oscillator], ids=["planar", "spatial"])
def test_linear_oscillator_response_and_multipliers_in_closed_form(tmp_path, scene):
    """Along the continued branch, the orbit's state at t = 0 is the steady response
    y = A cos(w t - phi), A = F / sqrt((k - m w^2)^2 + (c w)^2), tan phi = c w / (k - m w^2),
    to 1e-6 of A (and of A w); the two multipliers of the block's motion have the modulus
    exp(-zeta w_n T) (to 1e-6: central differences of a linear map), the others (the
    directions the guide, or the Euler parameters' norm, project away) vanish; doubling the
    difference step does not move them (a linear map)."""
    m, k, c, force = 2.0, 800.0, 4.0, 3.0
    family = family_of(scene(3.0), "frequency", 3.0, tmp_path)
    line = method.Continuation(family, 2.0, 4.5)
    x = family.settle(3.0, 5)[1]
    branch = line.run(line.first(x, 3.0, 1.0), 0.04, 12)
    nq = family.flow(3.0).model.nq
    assert branch.complete and len(branch.points) == 12 and not branch.specials
    for point in branch.points:
        w = 2 * math.pi * point.p
        amplitude = force / math.hypot(k - m * w * w, c * w)
        phase = math.atan2(c * w, k - m * w * w)
        scale = family.scale_at(family.flow(point.p))
        y0, v0 = point.x[1] * scale[1], point.x[nq + 1] * scale[nq + 1]
        assert y0 == pytest.approx(amplitude * math.cos(phase), abs=1e-6 * amplitude)
        assert v0 == pytest.approx(amplitude * w * math.sin(phase), abs=1e-6 * amplitude * w)
        moduli = np.sort(np.abs(point.multipliers))[::-1]
        decay = math.exp(-c / (2 * m) / point.p)
        assert moduli[:2] == pytest.approx([decay, decay], rel=1e-6)
        assert np.all(moduli[2:] < 1e-6)
    _, spread = line.resolve(branch.points[0])
    assert spread < 1e-8 and line.step == method.FD_STEP   # a linear map: its differences do not depend on the step


@pytest.mark.parametrize("scene", [linear_oscillator, spatial_linear_oscillator], ids=["planar", "spatial"])
def test_the_monodromy_along_the_joints_tangent_space_is_the_one_along_every_coordinate(tmp_path, scene):
    """The block on its guide has one degree of freedom: its map's state (planar 6, spatial
    14 coordinates) lies on a manifold of dimension 2, and the monodromy differenced along
    its two tangent directions (the map integrated 2 x 2 + 2 times with P_q) equals the one
    differenced along every coordinate (2n integrations, here in the test) to 1e-9 of its
    largest entry (measured 1.5e-11: the map is linear, and what is left is the
    integration's error, rtol 1e-11, over the difference step)."""
    family = family_of(scene(3.0), "frequency", 3.0, tmp_path)
    line = method.Continuation(family, 2.0, 4.5)
    orbit = line.first(family.settle(3.0, 5)[1], 3.0, 1.0)
    maps = []
    integrate = family.map
    family.map = lambda *a: maps.append(a) or integrate(*a)
    jac = line.jacobian(orbit.x, orbit.p)
    family.map = integrate
    h, n = method.FD_STEP, orbit.x.size
    full = np.column_stack([(integrate(orbit.x + h * e, orbit.p, 1) - integrate(orbit.x - h * e, orbit.p, 1)) / (2 * h)
                            for e in np.eye(n)])
    assert len(maps) == 2 * 2 + 2 and n > 2
    assert np.abs(jac[:, :n] + np.eye(n) - full).max() < 1e-9 * np.abs(full).max()


def grazing_frequencies(data):
    """The forcing frequencies (Hz) at which the block's linear response across the guide,
    F/k / sqrt((1 - r^2)^2 + (2 zeta r)^2), equals the clearance (below and above f_n)."""
    from scipy.optimize import brentq

    spring, load, guide = data["springs"][0], data["loads"][0], data["translational_joints"][0]
    m, k, c = data["bodies"][0]["mass"], spring["stiffness"], spring["damping"]
    wn, zeta = math.sqrt(k / m), c / (2 * math.sqrt(k * m))
    excess = lambda r: load["force"][1] / k / math.hypot(1 - r * r, 2 * zeta * r) - guide["clearance"]   # noqa: E731
    return [brentq(excess, 0.5, 1.0) * wn / (2 * math.pi), brentq(excess, 1.0, 1.5) * wn / (2 * math.pi)]


@pytest.mark.parametrize("start, low, high, side", [(13.5, 13.0, 14.8, 0), (19.0, 17.0, 19.5, 1)])
def test_impact_oscillator_grazes_where_the_linear_response_reaches_the_gap(tmp_path, start, low, high, side):
    """Continued towards resonance from either side, the branch grazes at the closed-form
    frequency (measured within 2e-7 from below, 1e-5 from above); without contact its
    amplitude is the linear response's. From above, the steps shrink into the grazing (the
    corrector slows where contact begins): 20 points reach it (from 19 Hz: 17.4092,
    17.4041, 17.4003, 17.3996 Hz at points 11-14)."""
    data = tomllib.loads(IMPACT.read_text())
    data["loads"][0]["frequency_hz"] = start
    family = family_of(data, "frequency", start, tmp_path)
    line = method.Continuation(family, low, high)
    x = family.settle(start, 30)[1]
    branch = line.run(line.first(x, start, 1.0 if side == 0 else -1.0), 0.02, 20)
    grazing = [s for s in branch.specials if s.kind == "grazing"]
    assert len(grazing) == 1
    assert grazing[0].p == pytest.approx(grazing_frequencies(data)[side], rel=2e-5)
    assert grazing[0].point.measures["amplitude"] == pytest.approx(1e-3, rel=1e-3)


def impact_oscillator_orbit(data, w, x):
    """The block's motion across the guide (y, y') integrated separately over one forcing
    period from x: m y'' + c y' + k y + F_c = F cos(w t), each face's two corners a contact
    F_c = 2 k_c d (1 + chi d' / v0) while d = |y| - clearance > 0 (Lankarani-Nikravesh, chi =
    3 (1 - e^2) / 4, v0 the approach rate at the onset, located as an event). Returns the
    state a period on, the largest contact force F_c over the period (N) and the largest
    |y| (m), each the maximum of the dense output refined by a bounded scalar search."""
    from scipy.optimize import minimize_scalar

    spring, load, guide = data["springs"][0], data["loads"][0], data["translational_joints"][0]
    m, k, c, f = data["bodies"][0]["mass"], spring["stiffness"], spring["damping"], load["force"][1]
    gap, kc = guide["clearance"], 2 * guide["stiffness"]
    chi = 0.75 * (1 - guide["restitution"] ** 2)
    t, y, end, onset = 0.0, np.array(x, float), 2 * math.pi / w, 1.0
    depth = lambda z: abs(z[0]) - gap   # noqa: E731

    def contact(z, v0):
        d = depth(z)
        return kc * d * (1 + chi * math.copysign(1.0, z[0]) * z[1] / v0) if d > 0 else 0.0

    def rhs(s, z):
        return [z[1], (f * math.cos(w * s) - c * z[1] - k * z[0] - math.copysign(contact(z, onset), z[0])) / m]

    def touch(s, z):
        return depth(z)
    touch.terminal = True
    peaks = {"force": 0.0, "y": 0.0}

    def largest(sol, a, b, v0):   # of the force and of |y| on this segment of the dense output
        grid = np.linspace(a, b, 400)
        for key, value in (("force", lambda s: contact(sol.sol(s), v0)), ("y", lambda s: abs(sol.sol(s)[0]))):
            i = int(np.argmax([value(s) for s in grid]))
            lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
            best = minimize_scalar(lambda s: -value(s), bounds=(lo, hi), method="bounded",
                                   options={"xatol": 1e-13}) if hi > lo else None
            peaks[key] = max(peaks[key], value(grid[i]), -best.fun if best is not None else 0.0)
    while t < end:
        sol = solve_ivp(rhs, (t, end), y, method="DOP853", rtol=1e-12, atol=1e-15, events=touch,
                        dense_output=True)
        largest(sol, t, sol.t[-1], onset)
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.status == 1:   # on a face: v0 at an onset; then off the surface, events off
            if math.copysign(1.0, y[0]) * y[1] > 0:
                onset = max(abs(y[1]), 1e-3)
            off = solve_ivp(rhs, (t, min(t + 1e-9, end)), y, method="DOP853", rtol=1e-12, atol=1e-15)
            t, y = off.t[-1], off.y[:, -1]
    return y, peaks["force"], peaks["y"]


def impact_oscillator_map(data, w, x):
    return impact_oscillator_orbit(data, w, x)[0]


def impact_oscillator_fixed_point(data, w, y):
    """The separate integration's own periodic orbit near y, by Newton on its period map
    (central differences): the state and the Jacobian of the map there."""
    for _ in range(8):
        scale = np.array([1e-9, 1e-9 * w])
        base = impact_oscillator_map(data, w, y)
        cols = [(impact_oscillator_map(data, w, y + e) - impact_oscillator_map(data, w, y - e)) / (2 * e[i])
                for i, e in enumerate(np.diag(scale))]
        reference = np.column_stack(cols)
        y = y - np.linalg.solve(reference - np.eye(2), base - y)
    return y, reference


def test_impacting_orbit_multipliers_against_a_separate_integration(tmp_path):
    """On the impacting branch above resonance (impacts on both faces each period), the
    multipliers of the block's motion across the guide (the 2 x 2 block of the monodromy in
    (y, y')) equal those of the same orbit integrated separately, with its onsets located
    as events and its monodromy by central differences: trace and determinant within 1 %
    (measured 0.13 % and 0.26 %: the engine's difference step against its onsets' noise,
    reduced.dynamics.continuation), and both say the same of the motion across the guide's
    stability. (The block's rocking, which the separate integration leaves out, is what
    makes this symmetric orbit unstable: the corner that strikes first turns it.)"""
    data = tomllib.loads(IMPACT.read_text())
    data["loads"][0]["frequency_hz"] = 18.0
    family = family_of(data, "frequency", 18.0, tmp_path)
    line = method.Continuation(family, 17.0, 18.0)
    x = family.settle(18.0, 30)[1]
    branch = line.run(line.first(x, 18.0, -1.0), 0.02, 40)
    impacting = [p for p in branch.points if p.measures["gap"] < 0]
    assert impacting, "the branch reaches the impacting orbits"
    point = impacting[-1]
    w = 2 * math.pi * point.p
    nq = family.flow(point.p).model.nq
    rows = [1, nq + 1]
    jac = line.jacobian(point.x, point.p)[:, :-1] + np.eye(point.x.size)
    engine_block = jac[np.ix_(rows, rows)]
    y = np.array([point.x[1] * family.scale[1], point.x[nq + 1] * family.scale[nq + 1]])
    y, reference = impact_oscillator_fixed_point(data, w, y)
    # the multipliers lie near a double one (sensitive as a square root): their sum and
    # product, the block's trace and determinant, are what is compared
    assert np.trace(engine_block) == pytest.approx(np.trace(reference), rel=0.01)
    assert np.linalg.det(engine_block) == pytest.approx(np.linalg.det(reference), rel=0.01)
    assert all(abs(m) < 1 for m in np.linalg.eigvals(reference)) == \
        all(abs(m) < 1 for m in np.linalg.eigvals(engine_block))


@pytest.mark.parametrize("hz", [15.0, 16.0])
def test_a_continued_orbits_peak_force_gap_and_energy_against_a_separate_integration(tmp_path, hz):
    """The stable impacting orbit the scene settles on below its fold (the block striking
    both faces each period, both corners of a face at once: the separate one-degree-of-freedom
    integration of impact_oscillator_orbit is its motion exactly): its measures, refined
    between the steps with the contacts' onset speeds, against that integration's own orbit
    (rtol 1e-12): the peak contact force within 1e-5 (measured 1e-6: 7.015 N at 15 Hz,
    13.640 N at 16 Hz), the amplitude within 1e-6 and the gap within 1e-9 m; the energy
    dissipated over the orbit equals the work of the load (a periodic orbit stores nothing;
    1e-5); and a time-domain run settled on the orbit from the scene's start (200 periods)
    has the same peak in its summary within 0.5 % (measured 1e-9)."""
    from pinbore.reduced.mechanism import outputs

    data = tomllib.loads(IMPACT.read_text())
    data["loads"][0]["frequency_hz"] = hz
    family = family_of(data, "frequency", hz, tmp_path)
    state, x, _ = family.settle(hz, 200)
    family.template = state
    point = method.Continuation(family, 10.0, 30.0).first(x, hz, 1.0)
    assert point.stable and point.measures["gap"] < 0
    w, nq = 2 * math.pi * hz, family.flow(hz).model.nq
    y = np.array([point.x[1] * family.scale[1], point.x[nq + 1] * family.scale[nq + 1]])
    _, force, largest = impact_oscillator_orbit(data, w, impact_oscillator_fixed_point(data, w, y)[0])
    measures = point.measures
    assert measures["peak_force"] == pytest.approx(force, rel=1e-5)
    assert measures["amplitude"] == pytest.approx(largest, rel=1e-6)
    assert measures["gap"] == pytest.approx(1e-3 - largest, abs=1e-9)
    assert measures["dissipated"] == pytest.approx(measures["work_in"], rel=1e-5)

    flow = family.flow(hz)
    flow.advance(state)   # the 201st period of the run from the scene's start
    summary = outputs.summary(flow.model, outputs.sample(flow.model, flow.last), flow.last, "complete", "")
    assert summary.clearance_joints["guide"].peak_normal_force_N == pytest.approx(measures["peak_force"], rel=5e-3)


def test_the_continuation_command_writes_the_response_and_agrees_with_direct_sweeps(tmp_path):
    """`pinbore dynamics --analysis continuation` on the shipped impact oscillator: the branch
    and its grazing (closed form); below grazing, where the orbit is the only one, the
    continued amplitudes are the linear response's within 1e-5 (refined between the steps),
    the directly swept ones within 1e-4 (after 60 periods, 5 s at 12 Hz, where the free
    decay exp(-zeta w_n t) leaves 5e-5); the table and the figure."""
    import csv
    import json

    from pinbore import cli

    out = tmp_path / "out"
    code = cli.main(["dynamics", str(IMPACT), "--analysis", "continuation", "--parameter", "frequency",
                     "--range", "12", "14.8", "--points", "24", "--transient", "60", "--sweeps", "5",
                     "--periods", "5", "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    assert code == (0 if summary["converged"] else 1)
    grazing = [b for b in summary["bifurcations"] if b["kind"] == "grazing"]
    data = tomllib.loads(IMPACT.read_text())
    assert grazing and grazing[0]["value"] == pytest.approx(grazing_frequencies(data)[0], rel=2e-5)
    with open(out / "continuation.csv") as f:
        branch = sorted(((float(r["value"]), float(r["amplitude_m"])) for r in csv.DictReader(f)
                         if float(r["value"]) < grazing[0]["value"]))
    with open(out / "sweeps.csv") as f:
        sweeps = [(float(r["value"]), float(r["amplitude_m"])) for r in csv.DictReader(f)
                  if float(r["value"]) < grazing[0]["value"] - 0.2]
    spring, load = data["springs"][0], data["loads"][0]
    m, k, c = data["bodies"][0]["mass"], spring["stiffness"], spring["damping"]

    def linear(hz):
        w = 2 * math.pi * hz
        return load["force"][1] / math.hypot(k - m * w * w, c * w)
    assert len(sweeps) == 6 and len(branch) >= 8
    for value, amplitude in branch:
        assert amplitude == pytest.approx(linear(value), rel=1e-5)
    for value, amplitude in sweeps:
        assert amplitude == pytest.approx(linear(value), rel=1e-4)
    assert (out / "response.png").stat().st_size > 10_000 and (out / "bifurcations.csv").exists()


def test_a_branch_that_runs_out_of_points_inside_the_range_is_marked_partial(tmp_path, write_scene):
    """Four points a way (--points 8) cannot reach from 3 Hz to either end of [1, 6] Hz from
    a step of 0.05 Hz (an arclength step grows by at most 1.5 a point: 0.05 (1.5 + 2.25 +
    3.375) = 0.36 Hz at most): the command keeps the 7 points it found, says where each way
    stopped and exits 1, not 0 as if the range were covered."""
    import json

    from pinbore import cli

    out = tmp_path / "out"
    code = cli.main(["dynamics", str(write_scene(linear_oscillator(3.0))), "--analysis", "continuation",
                     "--parameter", "frequency", "--range", "1", "6", "--points", "8", "--step", "0.05",
                     "--transient", "5", "--sweeps", "0", "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    assert code == 1 and not summary["converged"]
    assert "short of the range [1, 6]" in summary["reason"] and summary["points"] == 7


def test_an_integration_too_coarse_for_the_monodromy_warns(tmp_path):
    """The shaken panel's centre lies at (1.0, 0.5) m, 1e4 clearances of 0.1 mm from the
    origin: the integrator's error control, rtol |y| + atol per coordinate, allows rtol x 1e4
    clearances there (closed form), more than the monodromy's difference step 1e-4 at rtol
    1e-7: a warning naming integrator.rtol and the rtol that resolves it; at the shipped
    rtol 1e-9 (1e-5 of a clearance) none."""
    from pinbore.reduced.dynamics import studies

    path = ROOT / "scenes/reduced/deployed_panel_shaken.toml"
    for rtol, warns in ((1e-7, True), (1e-9, False)):
        data = tomllib.loads(path.read_text())
        data["integrator"]["rtol"] = rtol
        family = studies.MechanismFamily(studies.SceneFile(path, data), "frequency", 3.0)
        assert family.extent == pytest.approx(1.0 / 1e-4, rel=1e-6)
        assert family.resolution == pytest.approx(rtol * 1e4, rel=0.01)   # atol 1e-11 adds < 1 %
        scene = studies.scene_model(data).model_validate(data)
        warning = studies.resolution_warning(family, scene, str(path))
        assert (warning is not None) == warns
        if warns:
            assert "integrator.rtol" in warning and "integrator.rtol <= 1e-08" in warning


def test_a_turning_drive_is_continued_over_its_speed(tmp_path, write_scene):
    """The Flores slider-crank with Coulomb friction (mu 0.1) at 100 rpm, where a sweep by
    direct integration settles on a period-1 motion, continued over the crank's speed (its
    angle counts the periods elapsed; the coordinates are taken relative to the drive): the
    command finds the orbit, stable, and steps along the branch both ways. Two methods, one
    orbit: Newton on the period map from the state after 10 transient turns, and plain time
    marching from that state 40 turns on (the multipliers are below 0.4: the attractor is
    reached to 0.4^40), agree within the corrector's tolerance."""
    import json

    from pinbore import cli

    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    data["drive"]["speed_rpm"] = 100.0
    data["clearance_joints"][0]["friction"] = {"law": "coulomb_ambrosio", "mu": 0.1}
    data["integrator"]["rtol"] = 4e-8   # resolves the monodromy's differences (no warning)
    out = tmp_path / "out"
    cli.main(["dynamics", str(write_scene(data)), "--analysis", "continuation", "--parameter", "speed",
              "--range", "99", "101", "--points", "2", "--transient", "10", "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["points"] >= 3 and summary["start_stable"]   # a step each way
    assert not any("integrator.rtol" in w for w in summary["warnings"])   # the integration resolves the step
    # what the monodromy resolves of the stability is said, and warned of when coarse
    spread_warned = any("not resolved" in w for w in summary["warnings"])
    assert spread_warned == (summary["start_multiplier_spread"] > method.SPREAD_WARNING)

    family = family_of(data, "speed", 100.0, tmp_path)
    state, x, _ = family.settle(100.0, 10)
    family.template = state
    orbit = method.Continuation(family, 99.0, 101.0).first(x, 100.0, 1.0)
    assert np.max(np.abs(orbit.multipliers)) < 0.4
    flow = family.flow(100.0)
    marched = family.coordinates(flow, flow.advance(state, 40))
    assert np.linalg.norm(marched - orbit.x) <= family.tolerance * (1 + np.linalg.norm(orbit.x))


def test_the_shaken_panels_continued_peak_force_is_its_time_domain_runs(tmp_path):
    """The deployed panel shaken at 3.5 Hz (its pin sliding in its bore through a
    Hertz-Lankarani-Nikravesh contact): the orbit continuation finds from the state after 30
    periods has the peak contact force of the time-domain run's next periods, in their
    summaries, within 0.5 % (measured 6e-5: the orbit's tolerance)."""
    from pinbore.reduced.dynamics import parameters
    from pinbore.reduced.mechanism import outputs

    data = parameters.with_parameter(tomllib.loads((ROOT / "scenes/reduced/deployed_panel_shaken.toml").read_text()),
                                  "frequency", 3.5, "")
    family = family_of(data, "frequency", 3.5, tmp_path)
    state, x, _ = family.settle(3.5, 30)
    family.template = state
    orbit = method.Continuation(family, 3.0, 4.0).first(x, 3.5, 1.0)
    assert orbit.stable and orbit.measures["gap"] < 0
    flow = family.flow(3.5)
    for _ in range(2):
        state = flow.advance(state)
        summary = outputs.summary(flow.model, outputs.sample(flow.model, flow.last), flow.last, "complete", "")
        assert summary.peak_normal_force_N == pytest.approx(orbit.measures["peak_force"], rel=5e-3)


@pytest.mark.slow
def test_the_slider_crank_loses_stability_where_its_brute_force_attractor_doubles(tmp_path):
    """The Flores slider-crank with Coulomb friction (mu 0.1, rtol 4e-8), continued up from
    160 rpm: its period-1 orbit loses stability by a period doubling (a real multiplier
    through -1), and the switched doubled branch is stable there (supercritical). Another
    method, direct integration (300 turns settled, 20 sampled), finds a period-1 attractor
    at 164 rpm and a period-2 attractor at 166 rpm: the doubling lies between them, and the
    brute-force period-2 points lie on the doubled orbit converged at 166 rpm to within what
    the corrector's tolerance allows (the bench measured 0.024 um at 167 rpm; the doubled
    orbit's two points lie about 40 um apart at 166 rpm; the bound 1 um)."""
    from pinbore.reduced.dynamics import flow

    data = tomllib.loads((ROOT / "scenes/reduced/slider_crank_flores2004.toml").read_text())
    data["drive"]["speed_rpm"] = 160.0
    data["clearance_joints"][0]["friction"] = {"law": "coulomb_ambrosio", "mu": 0.1}
    data["integrator"]["rtol"] = 4e-8
    family = family_of(data, "speed", 160.0, tmp_path)
    state, x, _ = family.settle(160.0, 10)
    family.template = state
    line = method.Continuation(family, 150.0, 180.0)
    first, spread = line.resolve(line.first(x, 160.0, 1.0))
    assert first.stable and line.step > method.FD_STEP   # the integration's noise needs a larger step
    branch = line.run(first, 0.05, 16)
    flips = [s for s in branch.specials if s.kind == "period_doubling"]
    assert flips and 164.0 < flips[0].p < 166.0
    doubled = line.doubled(flips[0], 0.05, 10)
    assert doubled is not None and doubled.points[0].stable
    assert max(p.p for p in doubled.points) > 166.0   # it reaches the speed it is checked at

    for speed, period in ((164.0, 1), (166.0, 2)):
        here = family.flow(speed)
        samples, states = flow.poincare(here, here.start(), 300, 20)
        assert flow.period_of(samples) == period
    twice = method.Continuation(family, 150.0, 180.0, 2)
    twice.step = line.step
    near = min(doubled.points, key=lambda p: abs(p.p - 166.0))
    orbit = family.state(here, twice.first(near.x, 166.0, 1.0).x)
    ours = [here.observed(s)[:2] for s in (orbit, here.advance(orbit))]
    theirs = [here.observed(s)[:2] for s in states[-2:]]
    assert np.linalg.norm(ours[0] - ours[1]) > 5e-6   # a genuine period 2
    assert max(min(np.linalg.norm(a - b) for b in theirs) for a in ours) < 1e-6
