"""Stage 1: parametric Gmsh models of a pin in a bore (2D plane strain and 3D)."""
