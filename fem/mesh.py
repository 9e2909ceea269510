"""`pinbore mesh SCENE --out DIR`: the 2D or 3D gmsh model of an FE scene (its worn joint's,
when the scene names a wear file); write DIR/mesh.msh and DIR/preview.png. Needs Gmsh and the
scene model, not DOLFINx."""

from pathlib import Path

from pinbore.core import scene as scenes
from pinbore.core.output import atomic_directory
from pinbore.fem.scene import FemScene, worn_joint


def run(scene_path, out) -> int:
    scene = scenes.load(FemScene, scene_path)   # validated before Gmsh and matplotlib load
    worn = worn_joint(scene, Path(scene_path).parent, str(scene_path))   # its wear file, if any
    from pinbore.meshes import run as mesh_run   # noqa: PLC0415

    with atomic_directory(out) as tmp:
        mesh_run.write(scene.geometry, scene.sizing_of(worn), scene.load.direction_deg,
                       scene.mesh_options, tmp, worn)
    return 0
