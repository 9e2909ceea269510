"""Stage 2: DOLFINx contact between the pin and the bore (penalty or augmented Lagrangian)."""

if __name__ != "pinbore.fem":   # one module, one name: never a second copy as `fem`
    raise ImportError("fem/ is the package pinbore.fem: import pinbore.fem")
