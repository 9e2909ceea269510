"""Stage 3: calibration and ranking of contact stiffness laws against FE curves (issue 4)."""
