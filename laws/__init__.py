"""Contact laws for revolute clearance joints: elastic (force against approach) and
dissipative (hysteresis). Pure functions in SI units, the formula and its source in each
docstring. This package imports nothing from the stages, so every stage may use it.
"""

if __name__ != "pinbore.laws":   # one module, one name: never a second copy as `laws`
    raise ImportError("laws/ is the package pinbore.laws: import pinbore.laws")
