"""Gmsh models: the pin in its bore (`pin_in_bore`, 2D plane strain and 3D, tilt and edge
relief), the sizing that grades the mesh on the expected contact arc (`sizing`), the
geometry and meshing tables of a scene (`model`), the previews and `pinbore mesh` (`preview`,
`run`), and the flexible bodies of a mechanism, links and panels (`body`)."""

if __name__ != "pinbore.meshes":   # one module, one name: never a second copy as `meshes`
    raise ImportError("meshes/ is the package pinbore.meshes: import pinbore.meshes")
