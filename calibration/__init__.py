"""The contact laws calibrated on the FE (`pinbore calibrate`): every elastic law fitted (scale
and exponent) and ranked on the 2D curves, the sliced law of a finite pin (force and tilting
moment) on the 3D curves, the restitution e(v0) on the FE impacts; laws.json, the ranking,
the figures and the report's section."""

if __name__ != "pinbore.calibration":   # one module, one name: never a second copy as `calibration`
    raise ImportError("calibration/ is the package pinbore.calibration: import pinbore.calibration")
