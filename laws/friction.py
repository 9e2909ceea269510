"""Friction laws for the tangential force at a contact, as scalar functions of the compiled core
(cpp/mechanism/laws.h, pinbore.core.cpp.laws): the multibody engine evaluates these very
functions inside its right-hand side, and the tests check them against closed forms.

v is the slip velocity (m/s). Every law gives F, the friction force along the slip: the
sliding body feels -F, which opposes it. sgn v is 1 for v > 0 and -1 otherwise (at v = 0 the
regularised laws vanish and Dahl's rate is zero). Static laws give F, or the coefficient mu
that Ambrosio's regularised Coulomb force turns into F; the state-variable laws (Dahl,
LuGre, Iwan) give the rates of their states, which the integrator carries. Sources as in
[Cao2013] (its eqs. 12-20) and the primary sources named in each docstring (keys of
REFERENCES.md).
"""

from pinbore.core.cpp import laws as _core

# the laws (formulas and sources in their docstrings, cpp/mechanism/laws.h beside the code)
sgn = _core.sgn
coulomb = _core.coulomb
ambrosio_factor = _core.ambrosio_factor
ambrosio = _core.ambrosio
stribeck_polynomial = _core.stribeck_polynomial
linear_velocity = _core.linear_velocity
dahl_rate = _core.dahl_rate
lugre_g = _core.lugre_g
lugre_rate = _core.lugre_rate
lugre_force = _core.lugre_force
iwan_bilinear = _core.iwan_bilinear
iwan_return_map = _core.iwan_return_map
