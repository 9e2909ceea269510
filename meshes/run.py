"""`pinbore mesh`: write the gmsh model of a scene (mesh.msh) and a PNG preview."""

from pathlib import Path

import gmsh

from pinbore.meshes import pin_in_bore, preview
from pinbore.meshes.model import gmsh_session


def write(geometry, sizing, direction_deg, mesh, out: Path, worn=None) -> None:
    """mesh.msh (gmsh 4.1, physical groups as in meshes.model) and preview.png into `out`;
    `worn`: the worn joint of a geometry naming a wear_file (meshes.worn)."""
    with gmsh_session():
        pin_in_bore.build(geometry, sizing, direction_deg, mesh, worn)
        gmsh.write(str(out / "mesh.msh"))
        if geometry.dim == 2:
            preview.preview_2d(out / "preview.png", geometry, direction_deg, sizing.arc_half_angle)
        else:
            preview.preview_3d(out / "preview.png")
