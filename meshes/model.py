"""The geometry and meshing tables of a scene, and the physical-group tags every stage uses."""

import contextlib
import math
import threading
from typing import Literal

import numpy as np
import pydantic

from pinbore.core.output import abandon_native_work
from pinbore.core.scene import Strict
from pinbore.laws.relief import Relief

_meshing: list[threading.Event] = []   # per generate under way: set when its mesher is done


@contextlib.contextmanager
def gmsh_session():
    """A quiet gmsh session (errors only), finalized however the block ends, unless a stop
    left its mesher running (generate: then the next session waits for that mesher and
    finalizes first); yields the gmsh module (imported here: a scene is validated without
    Gmsh)."""
    import gmsh   # noqa: PLC0415

    for done in list(_meshing):   # a mesher a stop left running (the API's caller went on)
        done.wait()
        _meshing.remove(done)
        gmsh.finalize()
    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Verbosity", 1)
    try:
        yield gmsh
    finally:
        if all(done.is_set() for done in _meshing):
            gmsh.finalize()


def generate(gmsh, dim: int) -> None:
    """gmsh.model.mesh.generate(dim) in a thread of its own. Gmsh's mesher returns to Python
    only when it is done (tens of seconds for a mesh near the cell cap), so a Ctrl-C or
    SIGTERM would wait for it; here the main thread waits on it in short waits and takes the stop
    at once. A stop leaves the mesher running: the session is not finalized under it, and the
    process ends without the native exit handlers (core.output.abandon_native_work)."""
    failures, done = [], threading.Event()

    def mesh():
        try:
            gmsh.model.mesh.generate(dim)
        except Exception as err:   # noqa: BLE001 (raised again in the caller's thread)
            failures.append(err)
        finally:
            done.set()

    _meshing.append(done)
    try:   # a stop while the thread starts (start waits for it) leaves it meshing too;
        # not Thread.join: a stop raised inside it marks the thread ended (bpo-45274's fix)
        threading.Thread(target=mesh, name="gmsh mesher", daemon=True).start()
        while not done.wait(0.05):
            pass
    except BaseException:
        abandon_native_work()
        raise
    _meshing.remove(done)
    if failures:
        raise failures[0]


# Physical groups (cells of each body, facets of each boundary). Stages downstream use these.
PIN, HOUSING = 1, 2
HUB, PIN_SURFACE, BORE_SURFACE, HOUSING_EDGE = 11, 12, 13, 14
PIN_ENDS, HOUSING_ENDS = 15, 16  # 3D only: the planes z = 0 and z = length
SYMMETRY = 17                    # 3D half model: the mid-plane z = length / 2 of both bodies

DEFAULT_LAYERS = 12              # 3D: element layers along the modelled length
# The most cells a scene may ask for unless its mesh.max_cells says more. Beyond them a run
# takes hours on a workstation: Gmsh's size field is evaluated in Python (about 1 ms per
# cell: a 2D mesh of 7.6e5 cells was still meshing after 8 min) and the direct solver's
# factors grow faster than the dofs (3D: 88k dofs, 4e4 cells, take 116 s serial).
MAX_CELLS = {2: 250_000, 3: 150_000}


class Geometry(Strict):
    """Pin (with a rigid hub) inside the bore of an annular housing; SI units (m).

    3D: the housing's bore spans 0 <= z <= `length`; the pin as well, or `pin_overhang` (m)
    further beyond each end (a pin through a lug). `tilt_deg` tilts the pin about the axis
    through its middle normal to the load (the end z = length leans towards the load:
    edge loading); `relief_length` and `relief_depth` round the bore's edges (see
    Relief): a profile of micrometres that the contact sees exactly and the mesh, built
    cylindrical, does not.

    2D: `wear_file` (a wear.csv of `pinbore wear`) wears the bore and the pin: the bore's
    surface is r = bore_radius + h_bore(theta - bore_frame_deg), the pin's r = pin_radius -
    h_pin(theta - pin_frame_deg), theta the scene's angle (meshes.worn).
    """

    dim: Literal[2, 3]
    pin_radius: float = pydantic.Field(gt=0)
    bore_radius: float = pydantic.Field(gt=0)
    housing_radius: float = pydantic.Field(gt=0)
    hub_radius: float = pydantic.Field(gt=0)
    length: float | None = pydantic.Field(default=None, gt=0)
    tilt_deg: float = pydantic.Field(default=0.0, ge=-10, le=10)
    pin_overhang: float = pydantic.Field(default=0.0, ge=0)
    relief_length: float | None = pydantic.Field(default=None, gt=0)
    relief_depth: float | None = pydantic.Field(default=None, gt=0)
    wear_file: str | None = pydantic.Field(default=None, description=(
        "a wear.csv (pinbore wear): the bore and the pin worn by its depths against angle "
        "(2D); relative to the scene's folder"))
    bore_frame_deg: float | None = pydantic.Field(default=None, ge=-360, le=360, description=(
        "with wear_file: the angle (deg) of the bore's frame in the scene's, where the wear "
        "file's bore angle 0 lies (default 0)"))
    pin_frame_deg: float | None = pydantic.Field(default=None, ge=-360, le=360, description=(
        "with wear_file: the angle (deg) of the pin's frame in the scene's, where the wear "
        "file's pin angle 0 lies (default 0)"))

    @pydantic.model_validator(mode="after")
    def _consistent(self):
        if self.bore_radius <= self.pin_radius:
            raise ValueError("bore_radius must exceed pin_radius (clearance > 0)")
        if self.hub_radius >= self.pin_radius:
            raise ValueError("hub_radius must be smaller than pin_radius")
        if self.housing_radius <= self.bore_radius:
            raise ValueError("housing_radius must exceed bore_radius")
        if self.dim == 3 and self.length is None:
            raise ValueError("length is required when dim = 3")
        three_d = {"tilt_deg": self.tilt_deg or None, "pin_overhang": self.pin_overhang or None,
                   "relief_length": self.relief_length, "relief_depth": self.relief_depth}
        for key, value in three_d.items():
            if self.dim == 2 and value is not None:
                raise ValueError(f"{key} applies to dim = 3 only")
        if self.wear_file is not None and self.dim != 2:
            raise ValueError("wear_file applies to dim = 2 only (a wear.csv is a planar "
                             "joint's profiles)")
        for key in ("bore_frame_deg", "pin_frame_deg"):
            if getattr(self, key) is not None and self.wear_file is None:
                raise ValueError(f"{key} applies with wear_file only")
        if (self.relief_length is None) != (self.relief_depth is None):
            raise ValueError("relief_length and relief_depth go together")
        if self.relief_length is not None and self.relief_length >= self.length / 2:
            raise ValueError("relief_length must be below length / 2")
        if self.tilt_deg:
            reach = self.tilted_reach()
            if reach >= 0:
                raise ValueError(f"tilt_deg = {self.tilt_deg:g}: the tilted pin's end reaches "
                                 f"{reach * 1e6:.3g} um into the bore at rest; the tilt must "
                                 f"keep it inside (|tilt| below about "
                                 f"{math.degrees(2 * self.clearance / self.length):.3g} deg)")
        return self

    @property
    def relief(self) -> Relief | None:
        """The bore's edge relief, if the scene gives one."""
        return None if self.relief_length is None else Relief(self.relief_length, self.relief_depth)

    def bore_radius_at(self, z):
        """Bore radius (m) at axial positions z, with the edge relief."""
        z = np.asarray(z, dtype=float)
        if self.relief is None:
            return np.full_like(z, self.bore_radius)
        return self.bore_radius + self.relief.profile(z, 0.0, self.length)[0]

    @property
    def tilt_frame(self) -> np.ndarray:
        """The pin's tilt in the canonical frame (load along -y): a rotation about +x through
        the middle (0, 0, length / 2), turning +z towards -y."""
        a = math.radians(self.tilt_deg)
        return np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)],
                         [0.0, math.sin(a), math.cos(a)]])

    def tilted_reach(self) -> float:
        """How far (m) the tilted pin's surface reaches past the bore at rest, the pin's axis
        on the bore's (< 0: it stays clear), sampled over the pin's surface inside the bore."""
        t, z = np.meshgrid(np.linspace(0, 2 * np.pi, 721),
                           np.linspace(-self.pin_overhang, self.length + self.pin_overhang, 201))
        surface = np.stack([self.pin_radius * np.cos(t), self.pin_radius * np.sin(t),
                            z - self.length / 2], axis=-1).reshape(-1, 3) @ self.tilt_frame.T
        z_tilted = surface[:, 2] + self.length / 2
        inside = (z_tilted >= 0) & (z_tilted <= self.length)
        r = np.hypot(surface[inside, 0], surface[inside, 1])
        return float(np.max(r - self.bore_radius_at(z_tilted[inside])))

    @property
    def clearance(self) -> float:
        """Radial clearance c = R_bore - R_pin (m)."""
        return self.bore_radius - self.pin_radius


class MeshOptions(Strict):
    """Element sizes. Left out, pinbore chooses them from the expected contact arc.

    contact_size (m) on the contact arc; grading: growth of the size per unit distance from
    it; refine: halve every element size this many times (convergence studies); layers: 3D
    layers along the modelled length, closer towards the ends (default 12); symmetry: model
    half the length with the mid-plane as a plane of symmetry (default: whenever the scene
    is symmetric about it, that is without tilt); max_cells: the most cells the mesh may have
    (estimated before meshing; default MAX_CELLS: 2.5e5 in 2D, 1.5e5 in 3D).
    """

    contact_size: float | None = pydantic.Field(default=None, gt=0)
    grading: float = pydantic.Field(default=0.25, gt=0, le=1)
    refine: int = pydantic.Field(default=0, ge=0, le=6)
    layers: int | None = pydantic.Field(default=None, ge=1)
    symmetry: bool | None = None
    max_cells: int | None = pydantic.Field(default=None, ge=1)


def overhang_layers(layers: int) -> int:
    """Element layers of a pin running on beyond each end of the bore (growing outwards)."""
    return max(2, layers // 3)


def uses_symmetry(geometry: Geometry, mesh: MeshOptions) -> bool:
    """Whether the 3D model is the half z <= length / 2 (see MeshOptions)."""
    if geometry.dim == 2:
        return False
    return not geometry.tilt_deg if mesh.symmetry is None else mesh.symmetry
