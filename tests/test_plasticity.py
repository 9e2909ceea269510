"""The von Mises return map alone (pinbore.fem.plasticity.radial_return, the function the FE
runs) against closed-form stresses of linear hardening, and its consistent tangent against
finite differences of the map itself.

Along a strain path of fixed direction the radial return is exact whatever the step
(the flow direction does not turn), so the closed forms are met to round-off (1e-12 of the
stress): a looser tolerance would hide a wrong factor in the flow rule or the hardening."""

import numpy as np
import pytest

from pinbore.fem.plasticity import (ELASTIC, elastic_energy, hardening_tables, radial_return,
                                   table_end, von_mises)

E, NU, Y, H = 200e9, 0.3, 250e6, 10e9
MU, KAPPA = E / (2 * (1 + NU)), E / (3 * (1 - 2 * NU))
SQRT2 = np.sqrt(2.0)


def material(n=1, curve=(([0.0], [Y], H))):
    return (np.full(n, MU), np.full(n, KAPPA), np.zeros(n, dtype=np.int64),
            *hardening_tables([curve]))


def path(strains, curve=(([0.0], [Y], H))):
    """Stresses, plastic strains and p along a sequence of total strains (Mandel), each step
    returning from the last."""
    eps_p, p = np.zeros((1, 6)), np.zeros(1)
    out = []
    for eps in strains:
        stress, eps_p, p, tangent = radial_return(np.atleast_2d(eps), eps_p, p, *material(curve=curve))
        out.append((stress[0], eps_p[0].copy(), p[0], tangent[0]))
    return out


def test_uniaxial_stress_follows_the_bilinear_curve():
    """Uniaxial stress sigma_xx(eps_xx), the lateral strains found by Newton with the
    consistent tangent (sigma_yy = sigma_zz = 0): sigma = E eps up to Y, then
    Y + E_t (eps - Y/E), E_t = E H / (E + H); unloading elastic with slope E; and the lateral
    strains those of plastic incompressibility."""
    eps_p, p = np.zeros((1, 6)), np.zeros(1)
    lateral = 0.0
    history = np.concatenate([np.linspace(0, 0.01, 21)[1:], [0.009]])
    for exx in history:
        for _ in range(20):
            eps = np.array([[exx, lateral, lateral, 0, 0, 0]])
            stress, new_p, new_eq, tangent = radial_return(eps, eps_p, p, *material())
            r = stress[0, 1]
            if abs(r) < 1e-9 * Y:
                break
            lateral -= r / (tangent[0, 1, 1] + tangent[0, 1, 2])
        assert abs(stress[0, 2]) < 1e-9 * Y
        if exx == history[-1]:
            top = history[-2]
            peak = Y + E * H / (E + H) * (top - Y / E)
            assert stress[0, 0] == pytest.approx(peak - E * (top - exx), rel=1e-10)
            assert new_eq[0] == pytest.approx(p[0], abs=0)   # elastic unloading
        else:
            expected = E * exx if exx <= Y / E else Y + E * H / (E + H) * (exx - Y / E)
            assert stress[0, 0] == pytest.approx(expected, rel=1e-10)
            plastic = max(exx - expected / E, 0.0)
            assert new_eq[0] == pytest.approx(plastic, rel=1e-10, abs=1e-18)
            np.testing.assert_allclose(new_p[0, :3], [plastic, -plastic / 2, -plastic / 2],
                                       rtol=1e-10, atol=1e-18)
        eps_p, p = new_p, new_eq


def test_plane_strain_uniaxial_strain_path():
    """eps = (e, 0, 0), eps_zz = 0 (a plane-strain path): q = 2 mu e until q = Y, then
    p = (2 mu e - Y) / (3 mu + H); mean stress kappa e; sigma_xx = kappa e + 2q/3,
    sigma_yy = sigma_zz = kappa e - q/3; eps_p = p (1, -1/2, -1/2): the out-of-plane
    plastic strain is kept and sigma_zz follows it."""
    for e, (stress, eps_p, p, _) in zip(np.linspace(0, 0.01, 11)[1:],
                                        path([[e, 0, 0, 0, 0, 0] for e in np.linspace(0, 0.01, 11)[1:]])):
        plastic = max((2 * MU * e - Y) / (3 * MU + H), 0.0)
        q = 2 * MU * e - 3 * MU * plastic
        np.testing.assert_allclose(stress[:3], [KAPPA * e + 2 * q / 3, KAPPA * e - q / 3, KAPPA * e - q / 3],
                                   rtol=1e-12)
        assert p == pytest.approx(plastic, abs=1e-15)
        np.testing.assert_allclose(eps_p[:3], [plastic, -plastic / 2, -plastic / 2], atol=1e-15)
    assert plastic > 0 and eps_p[2] < 0


def test_plane_strain_shear_path():
    """eps = (e, -e, 0) (pure shear in the plane, isochoric): q = 2 sqrt3 mu e until Y, then
    linear hardening; sigma_xx = -sigma_yy = q / sqrt3, sigma_zz = 0; the same in the rotated
    frame as a shear strain gamma = 2e (Mandel sqrt2 eps_xy)."""
    strains = np.linspace(0, 0.004, 9)[1:]
    for e, (stress, _, p, _), (shear, _, p_shear, _) in zip(
            strains, path([[e, -e, 0, 0, 0, 0] for e in strains]),
            path([[0, 0, 0, SQRT2 * e, 0, 0] for e in strains])):
        plastic = max((2 * np.sqrt(3) * MU * e - Y) / (3 * MU + H), 0.0)
        q = Y + H * plastic if plastic > 0 else 2 * np.sqrt(3) * MU * e
        np.testing.assert_allclose(stress[:3], [q / np.sqrt(3), -q / np.sqrt(3), 0], atol=1e-12 * Y)
        assert shear[3] / SQRT2 == pytest.approx(q / np.sqrt(3), rel=1e-12)
        assert p == pytest.approx(plastic, abs=1e-15) and p_shear == pytest.approx(plastic, abs=1e-15)
    assert plastic > 0


def test_a_table_is_followed_segment_by_segment():
    """A table (0, Y), (0.002, Y + 50 MPa), (0.01, Y + 90 MPa): one large step over several
    segments lands where q_tr - 3 mu p = sigma_y(p), the same point as many small steps;
    beyond the table sigma_y stays at its last value (perfectly plastic)."""
    table = ([0.0, 0.002, 0.01], [Y, Y + 50e6, Y + 90e6], 0.0)
    direction = np.array([1, -1, 0, 0, 0, 0]) / np.sqrt(2)
    one = path([0.01 * direction], table)[-1]
    many = path([t * direction for t in np.linspace(0, 0.01, 50)[1:]], table)[-1]
    assert one[2] == pytest.approx(many[2], rel=1e-12)
    np.testing.assert_allclose(one[0], many[0], rtol=1e-10, atol=1e-6)
    q_trial = 2 * MU * np.sqrt(1.5) * 0.01
    assert q_trial - 3 * MU * one[2] == pytest.approx(np.interp(one[2], *table[:2]), rel=1e-12)
    far = path([0.1 * direction], table)[-1]
    assert far[2] > 0.01 and von_mises(far[0][None])[0] == pytest.approx(Y + 90e6, rel=1e-12)


@pytest.mark.parametrize("curve", [([0.0], [Y], H), ([0.0], [Y], 0.0),
                                   ([0.0, 0.001, 0.01], [Y, Y + 40e6, Y + 60e6], 0.0)],
                         ids=["linear", "perfect", "table"])
def test_consistent_tangent_matches_finite_differences(curve):
    """d sigma / d eps of the return map by central differences (step 1e-9 of the strain,
    relative error ~1e-7 from round-off and the O(h^2) term) against the tangent it returns,
    at elastic and plastic points in random directions, from a state that has yielded
    before; a point whose neighbourhood straddles a kink of the table is skipped."""
    rng = np.random.default_rng(1)
    n = 40
    eps_p0 = 1e-3 * rng.standard_normal((n, 6))
    eps_p0[:, :3] -= eps_p0[:, :3].mean(axis=1, keepdims=True)
    p0 = np.sqrt(2 / 3) * np.linalg.norm(eps_p0, axis=1)
    strain = eps_p0 + 3e-3 * rng.standard_normal((n, 6))
    args = (np.full(n, MU), np.full(n, KAPPA), np.zeros(n, dtype=np.int64), *hardening_tables([curve]))
    stress, _, p, tangent = radial_return(strain, eps_p0, p0, *args)
    h = 1e-9
    plastic = 0
    for a in range(6):
        step = np.zeros(6)
        step[a] = h
        up = radial_return(strain + step, eps_p0, p0, *args)
        down = radial_return(strain - step, eps_p0, p0, *args)
        smooth = (up[2] > p0) == (down[2] > p0)
        for k, (lo, hi) in enumerate(zip(curve[0], curve[0][1:])):
            smooth &= ~((np.minimum(up[2], down[2]) < hi) & (np.maximum(up[2], down[2]) > hi))
        fd = (up[0] - down[0]) / (2 * h)
        np.testing.assert_allclose(tangent[smooth, :, a], fd[smooth], rtol=0, atol=2e-6 * E)
        plastic += np.count_nonzero(smooth & (p > p0))
    assert plastic > 30 and np.all(np.abs(tangent - tangent.transpose(0, 2, 1)) < 1e-6 * E)


def test_an_elastic_point_never_yields_and_energy_is_that_of_hooke():
    """A point of an elastic body (ELASTIC) stays linear at any strain; the elastic energy
    density is sigma : eps / 2 with sigma = C eps."""
    strain = np.array([[0.05, -0.02, 0.0, 0.03, 0.0, 0.0]])
    args = (np.full(1, MU), np.full(1, KAPPA), np.full(1, ELASTIC, dtype=np.int64),
            *hardening_tables([]))
    stress, eps_p, p, tangent = radial_return(strain, np.zeros((1, 6)), np.zeros(1), *args)
    assert p[0] == 0 and not eps_p.any()
    np.testing.assert_allclose(stress[0], tangent[0] @ strain[0], rtol=1e-14)
    assert elastic_energy(stress, args[0], args[1])[0] == pytest.approx(0.5 * stress[0] @ strain[0], rel=1e-13)


def test_only_a_hardening_table_has_an_end():
    """The warning 'past the last pair of a hardening table' is for tables only: a linear
    law, perfectly plastic included (hardening_modulus = 0), holds for any strain."""
    from pinbore.fem.scene import Material

    Y = 250e6
    assert table_end(Material(E=2e11, nu=0.3, yield_stress=Y, hardening_modulus=0.0)) == np.inf
    assert table_end(Material(E=2e11, nu=0.3, yield_stress=Y)) == np.inf
    tabled = Material(E=2e11, nu=0.3, yield_stress=Y, hardening=[[0.0, Y], [0.02, 300e6]])
    assert table_end(tabled) == 0.02


def test_the_compiled_return_map_refuses_arrays_of_the_wrong_shape():
    """The compiled core checks what it is given: strains that are not (n, 6), a modulus
    short of a point, a curve that names a table it was not given, each a ValueError naming
    the rule (no read past an array)."""
    strain, eps_p, p = np.zeros((2, 6)), np.zeros((2, 6)), np.zeros(2)
    moduli, curve = (np.full(2, 8e10), np.full(2, 1.6e11)), np.zeros(2, np.int64)
    tables = hardening_tables([([0.0], [2e8], 1e9)])
    with pytest.raises(ValueError, match=r"must be \(n, 6\)"):
        radial_return(np.zeros((2, 5)), eps_p, p, *moduli, curve, *tables)
    with pytest.raises(ValueError, match="a value a point"):
        radial_return(strain, eps_p, p, np.full(1, 8e10), moduli[1], curve, *tables)
    with pytest.raises(ValueError, match="names a table"):
        radial_return(strain, eps_p, p, *moduli, np.full(2, 3, np.int64), *tables)


def test_the_return_map_refuses_curves_that_are_no_indices_and_tables_that_do_not_increase():
    strain, eps_p, p = np.zeros((1, 6)), np.zeros((1, 6)), np.zeros(1)
    moduli = (np.full(1, 8e10), np.full(1, 1.6e11))
    tables = hardening_tables([([0.0, 0.1], [2e8, 3e8], 0.0)])
    with pytest.raises(ValueError, match="integers"):
        radial_return(strain, eps_p, p, *moduli, np.array([0.7]), *tables)
    with pytest.raises(ValueError, match="names a table"):
        radial_return(strain, eps_p, p, *moduli, np.array([-5]), *tables)
    backwards = (tables[0][:, ::-1].copy(), *tables[1:])
    with pytest.raises(ValueError, match="strains increase|starts at plastic strain 0"):
        radial_return(strain, eps_p, p, *moduli, np.array([0]), *backwards)
