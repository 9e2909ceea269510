"""Stage 1: parametric Gmsh models of a pin in a bore (2D plane strain and 3D)."""

if __name__ != "pinbore.meshes":   # one module, one name: never a second copy as `meshes`
    raise ImportError("meshes/ is the package pinbore.meshes: import pinbore.meshes")
