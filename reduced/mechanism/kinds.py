"""The kinds of mechanism, in one registry: every command, the report and the benchmarks ask
here which kind a scene is and never branch on it themselves.

A kind names its scene model (reduced.mechanism.scene: pure pydantic, so that a scene is
validated before any model is built), its body kind's module (reduced.mechanism.planar or
.spatial, loaded only to build a model) and what its state's coordinates are (recorded in
summary.json). A flexible body (its FE modes in a floating frame) is a body of a kind, not a
kind: a mechanism mixes rigid and flexible bodies, and the core's body functions branch on the
body (cpp/mechanism/planar.h, spatial.h).
"""

import importlib
from dataclasses import dataclass
from pathlib import Path

from pinbore.core import scene as scenes
from pinbore.core.errors import InputError
from pinbore.reduced.mechanism.scene import PlanarScene, SpatialScene


@dataclass(frozen=True)
class Kind:
    name: str                  # "planar" or "spatial": the scene's `kind`, summary.json's `model`
    scene: type                # its scene model
    module: str                # its body kind's module
    coordinates: str           # its state's coordinates per body, for summary.json
    dimension: int
    description: str           # what the report says of its runs
    joint_caption: str         # what a clearance joint's figure shows

    def bodies(self):
        """The body kind's module: how its scenes become the model's arrays, its outputs'
        columns and its flows' coordinates."""
        return importlib.import_module(self.module)


KINDS = {
    "planar": Kind(
        "planar", PlanarScene, "pinbore.reduced.mechanism.planar",
        "x, y (m), phi (rad) of each body's centre of mass (a flexible body's mean-axis frame), "
        "then a flexible body's modal coordinates eta (m sqrt(kg))", 2,
        "rigid and flexible bodies in the plane (a flexible body: its FE modes in a floating "
        "frame); revolute clearance joints (a journal in its bore) and translational ones (a "
        "slider in its guide, four corner contacts)",
        "the journal centre inside the clearance circle and the normal contact force (a slider "
        "in its guide: its offset across the guide, its tilt and its four corners' normal forces)."),
    "spatial": Kind(
        "spatial", SpatialScene, "pinbore.reduced.mechanism.spatial",
        "x, y, z (m) of each body's centre of mass (a flexible body's mean-axis frame), Euler "
        "parameters e0..e3, then a flexible body's modal coordinates eta (m sqrt(kg))", 3,
        "rigid and flexible bodies in 3D on Euler parameters (a flexible body: its FE modes in a "
        "floating frame), the same ideal joints, drive, torsion springs "
        "and latches; cylindrical clearance joints cut into slices along the bore (a tilted "
        "journal loads its edge and feels a tilting moment), with shoulders, spherical ones (a "
        "ball in its socket) and translational ones",
        "contact forces against time (a journal: the slices' radial sum and the shoulders' axial "
        "force; a ball: its force on the socket; a slider: its offset, tilt and corner forces)."),
}


def kind_of(data: dict, source: str) -> Kind:
    """The kind of a scene's data (its `kind` key); one InputError line for another. A kind's
    former name is read as the kind (core.scene.normal_kind: with a FutureWarning)."""
    kind = scenes.normal_kind(data, source).get("kind")
    if not isinstance(kind, str) or kind not in KINDS:
        raise InputError(f"{source}: kind: {kind!r} is not a mechanism; valid: "
                         f"{', '.join(repr(k) for k in KINDS)}")
    return KINDS[kind]


def of_scene(scene) -> Kind:
    """The kind of a validated scene."""
    return KINDS[scene.kind]


def validate(data: dict, source: str):
    """The scene of its data, validated by its kind's model (one InputError line)."""
    data = scenes.normal_kind(data, source)
    return scenes.validate(kind_of(data, source).scene, data, source)


def load(path) -> object:
    """Read and validate a mechanism scene file of any kind."""
    path = Path(path)
    return validate(scenes.read_toml(path), str(path))
