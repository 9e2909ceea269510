"""Stage 2: DOLFINx contact between the pin and the bore (penalty or augmented Lagrangian)."""
