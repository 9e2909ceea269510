"""Stage 3: calibration and ranking of contact stiffness laws against FE curves."""

if __name__ != "pinbore.calibration":   # one module, one name: never a second copy as `calibration`
    raise ImportError("calibration/ is the package pinbore.calibration: import pinbore.calibration")
