"""Stage 4: planar multibody models with revolute clearance joints."""

if __name__ != "pinbore.reduced":   # one module, one name: never a second copy as `reduced`
    raise ImportError("reduced/ is the package pinbore.reduced: import pinbore.reduced")
