"""Contact laws for revolute clearance joints: elastic (force against approach),
dissipative (hysteresis), friction, and the sliced law of a finite pin (force and tilting
moment, `sliced`) with its pieces: laws as log-log tables (`tables`) and the bore's edge
relief (`relief`). Pure functions in SI units, the formula and its source in each
docstring. This package imports nothing from the stages, so every stage may use it.
"""

if __name__ != "pinbore.laws":   # one module, one name: never a second copy as `laws`
    raise ImportError("laws/ is the package pinbore.laws: import pinbore.laws")
