"""Contact laws for clearance joints: elastic (force against approach, `elastic`),
dissipative (hysteresis and restitution, `dissipative`), friction, sliding wear (Archard's,
`wear`), and the sliced law of a finite pin (force and tilting moment, `sliced`) with its
pieces: laws as log-log tables (`tables`) and the bore's edge relief (`relief`). Pure
functions in SI units, the formula and its source in each docstring. This package imports
nothing from the stages, so every stage may use it.

Two files between stages are defined here, for every floor that reads them: the laws file of
`pinbore calibrate` (`lawsfile`), read as callables by `load` (pinbore.laws.contact.load:
`pinbore.laws.load("laws.json")["liu"](d, rate, v0)`), and the worn profiles of `pinbore
wear` (`wearfile`).
"""

if __name__ != "pinbore.laws":   # one module, one name: never a second copy as `laws`
    raise ImportError("laws/ is the package pinbore.laws: import pinbore.laws")


def __getattr__(name):
    """`pinbore.laws.load`, imported on first use: importing a law (e.g. to validate a scene)
    does not load the laws file's model or the compiled damping laws."""
    if name == "load":
        from pinbore.laws.contact import load   # noqa: PLC0415

        return load
    raise AttributeError(f"module 'pinbore.laws' has no attribute {name!r}")
