"""The reduced body, defined once: the file `pinbore modes` writes (body.npz) and the
mechanism reads. NumPy only (no DOLFINx): a stage that reads a body does not load the FE.

body.npz holds, SI units, the body frame at the centre of mass with the mesh's axes (a plane
body's z entries are zero; n the flexible modes, N the FE nodes, k the interfaces):

    format, version         "pinbore-reduced-body", VERSION
    scene, scene_sha256     the modes scene it came from (its file name and its bytes' hash)
    mesh_sha256             of the nodes and cells below: the mesh the modes belong to
    dim                     2 (plane stress) or 3
    mass                    kg
    centre                  (3,) the centre of mass in the mesh frame (m)
    omega                   (n,) rad/s, ascending, the reduced body's free modes
    psi                     (N, 3, n) the modes at the nodes, M-normalised (m / sqrt(kg))
    nodes                   (N, 3) the FE nodes, body frame (m)
    cells                   (c, v) the mesh's cells as node indices (for pictures and points)
    second_moments          (3, 3) I_ab (kg m^2)
    s, S                    (3, 3, n), (3, 3, n, n) the inertia invariants (fem.modes.reduction)
    translation_coupling    (3, n) zero in the mean-axis frame (kept as its check)
    stiffening              (3, 3, n, n) K_G,ab, 1/s^2 per (rad/s)^2
    interfaces              (k,) names; interface_centres (k, 3) body frame (m);
    interface_translation   (k, 3, n); interface_rotation (k, 3, n): each mode's motion of
                            the interface's frame
    fixed_interface_omega   (n_f,) rad/s; full_omega (m,) the whole FE model's free modes

A file that does not fit (another format or version, a key missing, a shape that does not
agree with n, N or k, a number not finite, a body that is not physical) is one InputError
line naming the file and the rule.
"""

import hashlib
import zipfile
from dataclasses import dataclass, fields
from pathlib import Path
import numpy as np
import pydantic

from pinbore.core.errors import InputError
from pinbore.core.scene import Positive, Record, read_json

FORMAT = "pinbore-reduced-body"
VERSION = 1
BODY = "body.npz"
SUMMARY = "modes.json"
COMMAND = "modes"


@dataclass(frozen=True)
class ReducedBody:
    """A reduced flexible body, read from (or about to be written to) body.npz."""

    scene: str
    scene_sha256: str
    dim: int
    mass: float
    centre: np.ndarray
    omega: np.ndarray
    psi: np.ndarray
    nodes: np.ndarray
    cells: np.ndarray
    second_moments: np.ndarray
    s: np.ndarray
    S: np.ndarray
    translation_coupling: np.ndarray
    stiffening: np.ndarray
    interfaces: tuple[str, ...]
    interface_centres: np.ndarray
    interface_translation: np.ndarray
    interface_rotation: np.ndarray
    fixed_interface_omega: np.ndarray
    full_omega: np.ndarray

    @property
    def modes(self) -> int:
        return self.omega.size

    @property
    def mesh_sha256(self) -> str:
        return mesh_hash(self.nodes, self.cells)

    def interface(self, name: str) -> int:
        return self.interfaces.index(name)

    @property
    def inertia(self) -> np.ndarray:
        """The undeformed body's inertia tensor about its centre of mass (kg m^2):
        J = tr(I) 1 - I."""
        return np.trace(self.second_moments) * np.eye(3) - self.second_moments


MEAN_AXIS_TOLERANCE = 1e-6   # of mean_axis_residuals: round-off of a reduction is 1e-10


def mean_axis_residuals(body) -> tuple[float, float]:
    """How far the modes are from the mean-axis frame, as fractions: |1^T M_s Psi_a| /
    (sqrt(m) rho_g) (the centre of mass moved) and |x~^T M Psi| / (sqrt(m) rho_g^2) (the body
    turned), rho_g the radius of gyration (a mode is M-normalised: its own scale is 1)."""
    gyration = np.sqrt(np.trace(body.second_moments) / body.mass)
    scale = np.sqrt(body.mass) * gyration
    s = body.s
    turning = np.stack([s[1, 2] - s[2, 1], s[2, 0] - s[0, 2], s[0, 1] - s[1, 0]])
    return (float(np.abs(body.translation_coupling).max() / scale),
            float(np.abs(turning).max() / (scale * gyration)))


def mesh_hash(nodes: np.ndarray, cells: np.ndarray) -> str:
    h = hashlib.sha256()
    h.update(np.ascontiguousarray(nodes, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(cells, dtype="<i8").tobytes())
    return h.hexdigest()


def file_hash(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def write(path: Path, body: ReducedBody) -> None:
    """body.npz (uncompressed: it is read whole, and quickly)."""
    arrays = {f.name: getattr(body, f.name) for f in fields(ReducedBody)}
    arrays["interfaces"] = np.array(body.interfaces, dtype=str)
    arrays["cells"] = np.asarray(body.cells, dtype=np.int64)
    with open(path, "wb") as stream:
        np.savez(stream, format=FORMAT, version=VERSION, mesh_sha256=body.mesh_sha256, **arrays)


def read(path) -> ReducedBody:
    """The reduced body of a body.npz, checked (module docstring)."""
    path = Path(path)
    source = str(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {key: data[key] for key in data.files}
    except FileNotFoundError:
        raise InputError(f"{source}: no such reduced body (run pinbore {COMMAND} first)") from None
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
        raise InputError(f"{source}: not a reduced body written by pinbore {COMMAND} ({err})") from None
    if str(arrays.get("format", "")) != FORMAT:
        raise InputError(f"{source}: format: not a reduced body written by pinbore {COMMAND}")
    version = arrays.get("version", np.array(-1))
    if version.ndim != 0 or version.dtype.kind != "i" or int(version) != VERSION:
        raise InputError(f"{source}: version: {version} is not this pinbore's {VERSION}: run "
                         f"pinbore {COMMAND} again")
    values = {}
    for f in fields(ReducedBody):
        if f.name not in arrays:
            raise InputError(f"{source}: {f.name}: required key is missing (run pinbore "
                             f"{COMMAND} again)")
        values[f.name] = arrays[f.name]
    scalars = {"scene": "U", "scene_sha256": "U", "dim": "i", "mass": "f"}
    for key, kind in scalars.items():
        value = values[key]
        if value.ndim != 0 or value.dtype.kind != kind:
            raise InputError(f"{source}: {key}: not a single {'text' if kind == 'U' else 'number'}")
        values[key] = {"U": str, "i": int, "f": float}[kind](value)
    if values["interfaces"].ndim != 1 or values["interfaces"].dtype.kind != "U":
        raise InputError(f"{source}: interfaces: not a list of names")
    values["interfaces"] = tuple(str(name) for name in values["interfaces"])
    for key, value in values.items():
        if isinstance(value, np.ndarray) and value.dtype.kind not in "fi":
            raise InputError(f"{source}: {key}: not an array of numbers")
    body = ReducedBody(**values)
    _check(body, source, str(arrays.get("mesh_sha256", "")))
    return body


def _check(body: ReducedBody, source: str, mesh_sha256: str) -> None:
    n, N, k = body.omega.size, body.nodes.shape[0], len(body.interfaces)
    shapes = {"centre": (3,), "psi": (N, 3, n), "nodes": (N, 3), "second_moments": (3, 3),
              "s": (3, 3, n), "S": (3, 3, n, n), "translation_coupling": (3, n),
              "stiffening": (3, 3, n, n), "interface_centres": (k, 3),
              "interface_translation": (k, 3, n), "interface_rotation": (k, 3, n)}
    for key, shape in shapes.items():
        value = getattr(body, key)
        if value.shape != shape:
            raise InputError(f"{source}: {key}: shape {value.shape}, not {shape} ({n} modes, "
                             f"{N} nodes, {k} interfaces)")
    for f in fields(ReducedBody):
        value = getattr(body, f.name)
        if isinstance(value, np.ndarray) and value.dtype.kind == "f" and not np.all(np.isfinite(value)):
            raise InputError(f"{source}: {f.name}: a value is not a finite number")
    if body.dim not in (2, 3):
        raise InputError(f"{source}: dim: {body.dim} is neither 2 nor 3")
    if not (np.isfinite(body.mass) and body.mass > 0):
        raise InputError(f"{source}: mass: must be a positive, finite number")
    if n == 0 or np.any(body.omega <= 0) or np.any(np.diff(body.omega) < 0):
        raise InputError(f"{source}: omega: the frequencies must be positive and ascending")
    for key in ("omega", "fixed_interface_omega", "full_omega"):
        if getattr(body, key).ndim != 1:
            raise InputError(f"{source}: {key}: not a list of frequencies")
    if (body.cells.dtype.kind != "i" or body.cells.ndim != 2 or body.cells.size == 0
            or body.cells.min() < 0 or body.cells.max() >= N):
        raise InputError(f"{source}: cells: not node indices of the {N} nodes")
    if len(set(body.interfaces)) != k:
        raise InputError(f"{source}: interfaces: a name is given twice")
    I = body.second_moments
    scale = np.trace(I)
    if (not np.allclose(I, I.T, rtol=0, atol=1e-12 * scale)
            or np.linalg.eigvalsh((I + I.T) / 2).min() < -1e-12 * scale):
        raise InputError(f"{source}: second_moments: not symmetric positive semi-definite")
    if not np.allclose(sum(body.S[a, a] for a in range(3)), np.eye(n), atol=1e-6):
        raise InputError(f"{source}: S: the modes are not mass-normalised (sum_a S_aa = 1)")
    moving, turning = mean_axis_residuals(body)
    if moving > MEAN_AXIS_TOLERANCE:
        raise InputError(f"{source}: translation_coupling: the modes move the centre of mass "
                         "(not the mean-axis frame)")
    if turning > MEAN_AXIS_TOLERANCE:
        raise InputError(f"{source}: s: the modes turn the body (not the mean-axis frame)")
    K = body.stiffening
    if not np.allclose(K, K.transpose(1, 0, 3, 2), rtol=0, atol=1e-9 * max(np.abs(K).max(), 1e-300)):
        raise InputError(f"{source}: stiffening: not symmetric")
    if body.dim == 2 and (np.any(body.nodes[:, 2]) or np.any(body.psi[:, 2])
                          or np.any(body.interface_translation[:, 2])
                          or np.any(body.interface_rotation[:, :2])):
        raise InputError(f"{source}: dim: a plane body with motion out of its plane")
    if mesh_sha256 != body.mesh_sha256:
        raise InputError(f"{source}: mesh_sha256: the nodes and cells are not those the modes "
                         "were computed on")


class ModesSummary(Record):
    """modes.json: what `pinbore modes` computed, for a person and the report."""

    scene_file: str
    scene: dict
    dofs: int = pydantic.Field(ge=1)
    nodes: int = pydantic.Field(ge=1)
    cells: int = pydantic.Field(ge=1)
    mass_kg: Positive
    centre_m: list[float]
    inertia_kg_m2: list[list[float]]
    frequencies_Hz: list[Positive] = pydantic.Field(min_length=1)   # the reduced body's free modes
    fixed_interface_frequencies_Hz: list[Positive]
    full_frequencies_Hz: list[Positive]          # the whole FE model's free modes (if asked)
    reduction_error: list[float]                 # reduced / full - 1, mode by mode
    mean_axis_residual: float = pydantic.Field(ge=0, le=MEAN_AXIS_TOLERANCE)   # |1^T M Psi|, |x~^T M Psi| of sqrt(m) |X|
    rigid_residual: float = pydantic.Field(ge=0, allow_inf_nan=False)   # rigid eigenvalues / the first flexible one
    wall_time_s: dict
    platform: dict


def write_summary(path: Path, summary: ModesSummary) -> None:
    path.write_text(summary.model_dump_json(indent=2) + "\n")


def read_summary(path, source: str | None = None) -> ModesSummary:
    return read_json(ModesSummary, path, COMMAND, source)
