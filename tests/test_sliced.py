"""The sliced cylindrical-joint law (pinbore.laws.sliced) against closed forms of a linear
per-length law, convergence orders as the slices double, symmetry, the edge relief's arc,
the end correction and a law beyond its table; the table lookup it shares with the mechanism
engine (pinbore.laws.tables, the compiled core's Engine::elastic_force).

Notation: bore length L, slices n of width h = L/n, offsets s = z - L/2, approach
delta(s) = delta + theta s - r(z), per-length law f (N/m)."""

import math
import warnings

import numpy as np
import pytest

from pinbore.laws import elastic as el
from pinbore.laws import sliced as sl
from pinbore.laws import tables
from pinbore.core.cpp import mechanism as core
from pinbore.reduced.mechanism.layout import CONTACT_COLUMNS, CONTACT_STIFFNESS, CONTACT_TABLE

L = 0.02            # m, bore length
K = 1e11            # Pa, stiffness of the linear per-length law f = K delta
STEEL = dict(E_bore=207e9, nu_bore=0.3, E_pin=207e9, nu_pin=0.3)
TIGHT = el.Joint(r_bore=10.0e-3, r_pin=9.99e-3, length=L, **STEEL)    # c = 10 um
FLORES = el.Joint(r_bore=10.0e-3, r_pin=9.5e-3, length=L, **STEEL)    # c = 0.5 mm
NO_RELIEF = (0.0, 0.0)


def linear_table():
    """f = K delta tabulated: exponent 1, so the log-log table is exact at every delta."""
    return tables.tabulate(lambda d: K * d, 1e-12, 1e-3, 200)


def law_table(name, joint, points=600):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")      # the implicit laws' range: NaN in the table
        return tables.tabulate(lambda d: el.PUBLISHED[name](d, joint), 1e-10, 1e-4, points)


def run(delta, theta, slices, table, relief=NO_RELIEF, end_length=0.0, scale=1.0, compliance=0.0):
    return sl.sliced(delta, theta, L, slices, *table, *relief, end_length, scale, compliance)


def linear_closed_form(delta, theta):
    """F (N) and M (N m) of f = K <delta + theta s> over s in [-L/2, L/2], theta != 0.

    Full contact (delta >= |theta| L/2): F = K delta L, M = K theta int s^2 ds = K theta L^3/12.
    Partial contact (|delta| < |theta| L/2), theta > 0: contact where s > -a, a = delta/theta;
    with b = a + L/2 the contact length and u = s + a,
        F = K theta int_0^b u du = K theta b^2 / 2 = K/(2 theta) (delta + theta L/2)^2,
        M = K theta int_0^b u (u - a) du = K theta (b^3/3 - a b^2/2) = K theta b^2 (L - a)/6,
    which meets the full-contact forms at a = L/2 (M = K theta L^3/12). theta < 0 mirrors
    s -> -s: F the same with |theta|, M of opposite sign."""
    t = abs(theta)
    if delta >= t * L / 2:
        return K * delta * L, K * theta * L**3 / 12
    if delta <= -t * L / 2:
        return 0.0, 0.0
    a = delta / t
    b = a + L / 2
    return K * t * b**2 / 2, math.copysign(K * t * b**2 * (L - a) / 6, theta)


def orders(errors):
    """Observed orders log2(e_n / e_2n) between successive doublings."""
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


def fitted_order(slices, errors):
    """Least-squares slope of -ln(error) against ln(n)."""
    return -np.polyfit(np.log(slices), np.log(errors), 1)[0]


# ---- the table lookup shared with the mechanism engine

def test_the_engine_looks_laws_up_with_the_laws_table():
    """The engine's elastic force of a contact with a tabulated law (no linear stiffness) is
    pinbore.laws.tables' force to the bit, NaN beyond the table: it picks the contact's table
    and looks it up as the laws do."""
    grid_log0, grid_step, log_f = law_table("liu", TIGHT)
    contacts = np.zeros((2, CONTACT_COLUMNS))
    contacts[1, CONTACT_TABLE] = 1          # the second contact's law is the second table
    assert contacts[1, CONTACT_STIFFNESS] == 0.0
    laws = np.stack([np.full(log_f.size, np.log(1.0)), log_f])
    for d in (3.3e-12, 1e-9, 2.718e-7, 4e-6, 9.99e-5, 1.01e-4):
        expected = tables.table_force(d, grid_log0, grid_step, log_f)
        got = core.elastic_force(contacts, 1, d, grid_log0, grid_step, laws)
        assert got == expected or (math.isnan(got) and math.isnan(expected)), (d, got, expected)
    assert math.isnan(core.elastic_force(contacts, 1, 1.01e-4, grid_log0, grid_step, laws))


def test_table_is_exact_for_a_power_law_and_nan_beyond():
    """ln f is linear in ln delta on each segment: a power law K d^1.5 comes back to rounding
    (~1e-14: ln f ~ 30 carries ~30 eps) between grid points and below the grid (the first
    segment's power law continues); above the grid, or where the table is NaN, NaN."""
    law = lambda d: 3e13 * d**1.5                       # noqa: E731
    table = tables.tabulate(law, 1e-9, 1e-4, 50)
    for d in (3.3e-12, 1e-9, 2.718e-7, 9.99e-5, 1e-4):
        assert tables.table_force(d, *table) == pytest.approx(law(d), rel=1e-12)
    assert math.isnan(tables.table_force(1.01e-4, *table))
    grid_log0, grid_step, log_f = table
    cut = log_f.copy()
    cut[30:] = np.nan
    assert math.isnan(tables.table_force(math.exp(grid_log0 + 29.5 * grid_step), grid_log0, grid_step, cut))
    assert np.isfinite(tables.table_force(math.exp(grid_log0 + 28.5 * grid_step), grid_log0, grid_step, cut))


# ---- closed forms

@pytest.mark.parametrize("slices", [1, 2, 3, 7, 64])
def test_untilted_pin_carries_f_times_length(slices):
    """theta = 0, no relief, no end length: every slice has the approach delta, so
    F = sum f(delta) L/n = f(delta) L for any n (to the rounding of n equal terms), M = 0 (the
    offsets are exactly antisymmetric), z_F = L/2, all the length in contact. Nonlinear law
    (Liu's), to show nothing depends on the law's shape."""
    table = law_table("liu", TIGHT)
    delta = 2e-6
    force, moment, z_f, contact = run(delta, 0.0, slices, table)
    f = tables.table_force(delta, *table)
    assert force == pytest.approx(f * L, rel=1e-13)
    assert abs(moment) <= 1e-13 * force * L
    assert z_f == pytest.approx(L / 2, rel=1e-12)
    assert contact == pytest.approx(L, rel=1e-13)


@pytest.mark.parametrize("slices", [1, 2, 5, 16, 100])
def test_linear_law_in_full_contact(slices):
    """f = K delta with delta > |theta| L/2 (full contact): the midpoint rule integrates the
    linear F integrand exactly, F = K delta L for every n. M's integrand K (delta + theta s) s
    is quadratic; the midpoint sum gives K theta h sum s_i^2 = K theta L^3/12 (1 - 1/n^2)
    (sum over midpoints of s_i^2 = n h^2 (n^2 - 1)/12), exactly, the closed form to order h^2."""
    delta, theta = 5e-6, 2e-4
    force, moment, z_f, _ = run(delta, theta, slices, linear_table())
    closed_f, closed_m = linear_closed_form(delta, theta)
    assert force == pytest.approx(closed_f, rel=1e-13)
    assert moment == pytest.approx(closed_m * (1 - 1 / slices**2), rel=1e-12, abs=1e-14 * closed_m)
    assert z_f == pytest.approx(L / 2 + moment / force, rel=1e-14)


def test_linear_law_in_partial_contact_closed_form_and_order():
    """f = K delta, partial contact with the contact edge at z0 = L/3 (delta = theta L/6): F and
    M against `linear_closed_form`. The midpoint rule is exact on the slices wholly in or out
    of contact (F's integrand is linear there); the one slice holding the edge, the edge at
    the fraction xi of it, m = min(xi, 1 - xi), gives F_n - F = -K theta (m h)^2 / 2
    (integrate the hinge K theta <z - z0> over the slice: the exact part is
    K theta h^2 (1 - xi)^2/2, the midpoint K theta h^2 <1/2 - xi>). So the kink is
    no loss of order: the error is O(h^2), from one slice instead of summed over n, but it
    jumps with the edge's place in its slice. z0 = L/3 sits at xi = 1/3 or 2/3 as n doubles
    (n/3 mod 1), m = 1/3 always: F's error is exactly (m h / (2L/3))^2 relative, the
    observed order exactly 2. M has the same edge error plus the smooth O(h^2) of its
    quadratic integrand: order 2 within 0.25 (the two parts shift against each other).
    The contact length, a count of slices, is first order: within h/2 of 2L/3."""
    table = linear_table()
    theta = 1e-3
    delta = theta * L / 6
    closed_f, closed_m = linear_closed_form(delta, theta)
    assert closed_f == pytest.approx(K / (2 * theta) * (delta + theta * L / 2) ** 2)
    slices = [4 * 2**j for j in range(9)]
    errors_f, errors_m = [], []
    for n in slices:
        force, moment, z_f, contact = run(delta, theta, n, table)
        expected = -K * theta * (L / n / 3) ** 2 / 2
        assert force - closed_f == pytest.approx(expected, rel=1e-6)
        assert abs(contact - 2 * L / 3) <= L / n / 2 * (1 + 1e-12)
        assert z_f == pytest.approx(L / 2 + moment / force, rel=1e-14)
        errors_f.append(abs(force / closed_f - 1))
        errors_m.append(abs(moment / closed_m - 1))
    assert orders(errors_f) == pytest.approx(2.0, abs=1e-4)
    assert np.all(np.abs(orders(errors_m) - 2) < 0.25)
    assert errors_m[-1] < 1e-5


@pytest.mark.parametrize("delta", [-4e-6, 0.0, 3e-6, 9.9e-6])
def test_linear_partial_contact_converges_to_the_closed_form(delta):
    """Edges elsewhere (delta from barely touching to barely full, theta L/2 = 1e-5): the
    error is bounded by the edge slice's K theta (h/2)^2 / 2 plus M's smooth part, so at
    n = 4096 (h = 4.9 um) F within 1e-5 and M within 1e-4 relative of the closed form."""
    theta = 1e-3
    force, moment, _, _ = run(delta, theta, 4096, linear_table())
    closed_f, closed_m = linear_closed_form(delta, theta)
    assert force == pytest.approx(closed_f, rel=1e-5)
    assert moment == pytest.approx(closed_m, rel=1e-4)


# ---- convergence for nonlinear laws

@pytest.mark.parametrize("name, joint", [("liu", TIGHT), ("johnson", FLORES)])
@pytest.mark.parametrize("delta, theta", [(5e-6, 2e-4), (1e-6, 5e-4)], ids=["full", "partial"])
def test_order_two_for_nonlinear_laws(name, joint, delta, theta):
    """Nonlinear per-length laws (Liu's, Johnson's line contact, tabulated on 600 points):
    F and M at n = 16 ... 512 against n = 65536 (whose own error, ~(16/65536)^2 = 6e-8 of
    n = 16's, is far below the differences measured). The midpoint rule is O(h^2) for a
    smooth integrand; here the integrand has kinks: the contact edge (partial contact,
    delta = 1e-6 < theta L/2 = 5e-6) and, much smaller, the table's own slope changes at its
    grid points (log-log interpolation). Each kink costs one slice an O(h^2) error whose
    coefficient jumps with the kink's place in its slice, so the order between successive
    doublings scatters (measured 1.0-3.2 for Johnson in partial contact, whose law is nearly
    linear near delta = 0, i.e. a true kink), but the least-squares order over the range is
    2 within 0.15 (measured 1.99-2.08)."""
    table = law_table(name, joint)
    reference = run(delta, theta, 1 << 16, table)
    slices = np.array([16 * 2**j for j in range(6)])
    errors_f, errors_m = [], []
    for n in slices:
        force, moment, _, _ = run(delta, theta, int(n), table)
        errors_f.append(abs(force / reference[0] - 1))
        errors_m.append(abs(moment / reference[1] - 1))
    assert fitted_order(slices, errors_f) == pytest.approx(2.0, abs=0.15)
    assert fitted_order(slices, errors_m) == pytest.approx(2.0, abs=0.15)
    assert errors_f[0] < 5e-3      # 16 slices already give F within 0.5 % (measured 0.18 %)


# ---- symmetry, relief, ends, range

@pytest.mark.parametrize("slices", [5, 16])
@pytest.mark.parametrize("delta", [3e-6, -1e-6])
def test_moment_changes_sign_with_the_tilt(slices, delta):
    """Without relief, theta -> -theta mirrors the approach about the mid-plane
    (delta(s; -theta) = delta(-s; theta)): F the same, M opposite, z_F mirrored. The
    offsets are exactly antisymmetric, so only the summation order differs (rounding)."""
    table = law_table("liu", TIGHT)
    plus = run(delta, 4e-4, slices, table)
    minus = run(delta, -4e-4, slices, table)
    assert plus[1] > 0
    assert minus[0] == pytest.approx(plus[0], rel=1e-13)
    assert minus[1] == pytest.approx(-plus[1], rel=1e-12)
    assert minus[2] == pytest.approx(L - plus[2], rel=1e-12)
    assert minus[3] == pytest.approx(plus[3], rel=1e-13)


def test_edge_relief_lowers_the_end_slices_approach_by_the_arc():
    """A relief over l = 2 mm to d = 3 um at each end, 20 slices of 1 mm: the end slices'
    midpoints lie x = 1.5 mm and 0.5 mm into the relieved zones, the rest is cylindrical.
    Their approach drops by the sagitta r - sqrt(r^2 - x^2), r = (l^2 + d^2)/(2d), evaluated
    here independently in the cancellation-free form x^2 / (r + sqrt(r^2 - x^2)) (agreement
    to 1e-9 of the depth: the direct form loses ~eps r/depth = 4e-11 of it). F is then the
    sum of K delta_i h over the slices (linear law, so exact), below the unrelieved K delta L."""
    relief_length, relief_depth = 2e-3, 3e-6
    table = linear_table()
    delta, n = 2e-6, 20
    z, approach, f = sl.sliced_profile(delta, 0.0, L, n, *table, relief_length, relief_depth, 0.0, 1.0, 0.0)
    arc = (relief_length**2 + relief_depth**2) / (2 * relief_depth)
    into = np.clip(relief_length - np.minimum(z, L - z), 0.0, None)
    sagitta = into**2 / (arc + np.sqrt(arc**2 - into**2))
    assert np.count_nonzero(sagitta) == 4
    assert sagitta[0] == pytest.approx(relief_depth * (1.5 / 2) ** 2, rel=1e-3)   # ~ x^2/(2r)
    assert np.allclose(approach, delta - sagitta, rtol=0, atol=1e-9 * relief_depth)
    assert np.allclose(f, K * np.clip(approach, 0, None), rtol=1e-13, atol=0)
    force, moment, z_f, contact = run(delta, 0.0, n, table, (relief_length, relief_depth))
    assert force == pytest.approx(np.sum(K * np.clip(delta - sagitta, 0, None) * L / n), rel=1e-12)
    assert force < K * delta * L
    assert abs(moment) <= 1e-13 * force * L
    assert contact == pytest.approx(L - L / n * np.count_nonzero(delta - sagitta <= 0), rel=1e-13)


@pytest.mark.parametrize("end_length", [1.5e-3, -0.4e-3])
@pytest.mark.parametrize("slices", [1, 8])
def test_end_length_adds_the_law_at_each_end(end_length, slices):
    """Each end adds end_length (m, either sign) of per-length law at its end slice's
    approach, moment arm that of the end slice: F(e) - F(0) = e (f_first + f_last),
    M(e) - M(0) = e (f_first s_first + f_last s_last); with one slice that slice takes both
    ends (s = 0). Linear law, tilted, full contact: f at the end slices in closed form."""
    table = linear_table()
    delta, theta = 5e-6, 2e-4
    base = run(delta, theta, slices, table)
    ended = run(delta, theta, slices, table, end_length=end_length)
    s_first, s_last = -L / 2 + L / slices / 2, L / 2 - L / slices / 2
    f_first, f_last = K * (delta + theta * s_first), K * (delta + theta * s_last)
    assert ended[0] - base[0] == pytest.approx(end_length * (f_first + f_last), rel=1e-9)
    assert ended[1] - base[1] == pytest.approx(end_length * (f_first * s_first + f_last * s_last),
                                               rel=1e-9, abs=1e-12 * base[0] * L)
    assert ended[3] == base[3]                  # the contact length counts slices only


def test_a_law_beyond_its_table_gives_nan():
    """The reduced model's tables hold NaN beyond their range (and Johnson's law has none
    beyond its largest approach): one slice there makes F, M and z_F NaN, not a number."""
    grid_log0, grid_step, log_f = linear_table()
    cut = log_f.copy()
    top = 4e-6
    cut[np.exp(grid_log0 + grid_step * np.arange(cut.size)) > top] = np.nan
    table = (grid_log0, grid_step, cut)
    inside = run(3e-6, 0.0, 8, table)
    assert inside[0] == pytest.approx(K * 3e-6 * L, rel=1e-12)
    tilted = run(3e-6, 2e-4, 8, table)         # the end z = L reaches 3e-6 + 1.75e-6 > top
    assert all(math.isnan(v) for v in tilted[:3])
    johnson = law_table("johnson", TIGHT)      # c = 10 um: no solution above ~5 um
    assert all(math.isnan(v) for v in run(1e-6, 1e-3, 16, johnson)[:3])


def test_no_contact_gives_zero_force_and_nan_resultant():
    force, moment, z_f, contact = run(-1e-6, 1e-4, 16, linear_table())   # reaches -1e-6 + 1e-6
    assert (force, moment, contact) == (0.0, 0.0, 0.0) and math.isnan(z_f)


# ---- how many slices

def test_slices_for_one_percent_in_force():
    """`slices_for_force` doubles n from 4 until F changes by < 0.5 % (Richardson: the error of
    F_n is then < 1 % for any order >= 1) and, with a contact edge inside, >= 8 slices in
    contact. Against the linear closed form:
    - full contact (F exact for any n): 4;
    - edge at z0 = L/3: F_n's error is (m h / (2L/3))^2, m = 1/3 (see the partial-contact
      test): F_8 -> F_16 changes by 0.29 %, but at n = 8 only five slices (midpoints beyond
      L/3) are in contact; at 16 eleven are, and F_16 -> F_32 changes by 0.07 %: 16, whose
      error is (1/32)^2 = 0.1 %;
    - contact over 1 % of the length: n resolves it with 8 slices (1024), error < 1 %;
    - edges elsewhere: the error of the n returned < 1 %;
    - no contact: 4 (F = 0)."""
    table = linear_table()
    theta = 1e-3
    assert sl.slices_for_force(5e-6 + theta * L / 2, theta, L, *table) == 4
    assert sl.slices_for_force(theta * L / 6, theta, L, *table) == 16
    assert sl.slices_for_force(-0.49 * theta * L, theta, L, *table) == 1024
    assert sl.slices_for_force(-0.6 * theta * L, theta, L, *table) == 4
    for fraction in np.linspace(-0.49, 0.49, 23):
        delta = fraction * theta * L
        n = sl.slices_for_force(delta, theta, L, *table)
        closed_f, _ = linear_closed_form(delta, theta)
        assert abs(run(delta, theta, n, table)[0] / closed_f - 1) < 0.01, (fraction, n)


# ---- the shared bulk compliance

def test_split_compliance_of_a_linear_law_is_the_series_spring():
    """f = K delta with a compliance c taken out leaves f_loc = K u / (1 - c K): springs in
    series, 1/K = 1/K_loc + c (closed form); the table is exact for a power law."""
    c = 0.4 / K
    table = tables.split_compliance(*linear_table(), c)
    for u in (1e-9, 3e-7, 1e-5):
        assert tables.table_force(u, *table) == pytest.approx(K * u / (1 - c * K), rel=1e-10)
    assert tables.largest_compliance(*linear_table()) == pytest.approx(1 / K, rel=1e-10)
    with pytest.raises(ValueError, match="compliance"):
        tables.split_compliance(*linear_table(), 1.01 / K)


def test_split_compliance_ends_where_a_stiffening_law_outgrows_it():
    """f = K delta^2 / d0: u = delta - c f grows while 2 c K delta / d0 < 1, i.e. up to
    delta* = d0 / (2 c K); the split table ends there (NaN beyond) and holds below it
    (closed form: f at delta = u + c f, the root of c K/d0 delta^2 - delta + u = 0)."""
    d0, c = 1e-6, 0.1 / K
    table = tables.tabulate(lambda d: K * d**2 / d0, 1e-12, 1e-3, 400)
    local = tables.split_compliance(*table, c)
    star = d0 / (2 * c * K)
    top = star - c * K * star**2 / d0                 # u at delta*
    assert math.exp(local[0] + local[1] * (local[2].size - 1)) == pytest.approx(top, rel=0.05)
    assert math.isnan(tables.table_force(1.1 * top, *local))
    for u in (1e-9, 1e-7, 0.5 * top):
        q = c * K / d0
        delta = (1 - math.sqrt(1 - 4 * q * u)) / (2 * q)
        assert tables.table_force(u, *local) == pytest.approx(K * delta**2 / d0, rel=1e-3)
    assert tables.largest_compliance(*table, up_to=1e-7) == pytest.approx(d0 / (2 * K * 1e-7), rel=0.05)


@pytest.mark.parametrize("name, joint", [("liu", TIGHT), ("johnson", FLORES)])
@pytest.mark.parametrize("fraction", [0.3, 0.8])
def test_untilted_pin_with_bulk_compliance_carries_the_section_law(name, joint, fraction):
    """The long-pin limit: a straight pin (theta = 0, a = 1, e = 0) carries f(delta) L for any
    bulk compliance, the split law and the shared displacement c_b F / L undoing each other
    (module docstring). Reference: the section law itself. Tolerance: the split table's
    interpolation (600 points over six decades; 1e-5 measured scale of the log-log error)."""
    table = law_table(name, joint)
    bulk = fraction * tables.largest_compliance(*table)
    local = tables.split_compliance(*table, bulk)
    for delta in (2e-7, 3e-6, 2e-5):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            expected = el.PUBLISHED[name](np.array([delta]), joint)[0] * L
        force, moment, _, _ = run(delta, 0.0, 16, local, compliance=bulk)
        assert force == pytest.approx(expected, rel=2e-4)
        assert moment == pytest.approx(0.0, abs=1e-12 * force * L)


@pytest.mark.parametrize("slices", [1, 8, 64])
def test_bulk_compliance_leaves_the_force_and_stiffens_the_tilt(slices):
    """Linear law f = K delta, bulk compliance c, full contact: the local law is K_loc u,
    K_loc = K / (1 - c K). The uniform part carries F: F = K_loc L (delta - c F / L) gives
    F = K delta L (the section law's), while the tilt acts on the local springs alone:
    M = K_loc theta sum z_i^2 L/n = K_loc theta L^3/12 (1 - 1/n^2) (midpoint sums of z^2),
    1 / (1 - c K) times the moment of independent slices of the section law. Reference:
    these closed forms, to the shared approach's tolerance (1e-12) and round-off."""
    c = 0.5 / K
    local = tables.split_compliance(*linear_table(), c)
    delta, theta = 4e-6, 2e-4                       # delta > theta L/2 = 2e-6: full contact
    force, moment, resultant, _ = run(delta, theta, slices, local, compliance=c)
    k_loc = K / (1 - c * K)
    assert force == pytest.approx(K * delta * L, rel=1e-9)
    assert moment == pytest.approx(k_loc * theta * L**3 / 12 * (1 - 1 / slices**2),
                                   rel=1e-9, abs=1e-12)
    plain = run(delta, theta, slices, linear_table())
    assert moment == pytest.approx(plain[1] / (1 - c * K), rel=1e-9, abs=1e-12)


def test_bulk_compliance_in_partial_contact_is_the_closed_form_at_the_shared_approach():
    """Partial contact, linear law: the slices see x = delta - c F / L; F(x) is the linear
    closed form (linear_closed_form with K_loc), so x solves x + c F(x) / L = delta, a
    quadratic in x here, solved independently (numpy roots). F, M at 1024 slices against
    the closed form at that x: the partial-contact midpoint error (order 2, 1e-5 at 1024)."""
    c = 0.5 / K
    k_loc = K / (1 - c * K)
    local = tables.split_compliance(*linear_table(), c)
    delta, theta = 1e-6, 4e-4                       # theta L/2 = 4 um: one end lifts off
    # F(x) = K_loc/(2 theta) (x + h)^2 while |x| < h = theta L/2, so in y = x + h
    # x + c F(x) / L = delta reads q y^2 + y - (delta + h) = 0, q = c K_loc / (2 theta L)
    h = theta * L / 2
    q = c * k_loc / (2 * theta * L)
    y = max(np.roots([q, 1.0, -(delta + h)]).real)
    x = y - h
    assert abs(x) < h
    a, b = x / theta, y / theta                     # as in linear_closed_form
    f_exact = k_loc * theta * b**2 / 2
    m_exact = k_loc * theta * b**2 * (L - a) / 6
    force, moment, _, _ = run(delta, theta, 1024, local, compliance=c)
    assert force == pytest.approx(f_exact, rel=1e-5)
    assert moment == pytest.approx(m_exact, rel=1e-5)
