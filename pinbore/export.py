"""`pinbore export`: the calibrated contact laws of a laws file as tables another multibody code
reads, with a short adapter for Exudyn [Gerstmayr2023].

For each law, on the multibody model's own grid (reduced.mechanism.model: GRID_POINTS
penetrations spaced evenly in ln d from GRID_LOW to BLOW_UP_FRACTION of the pin's radius),
`<law>.csv` holds the approach d (m) and the elastic force F = L P(d) (N) of the joint; between
rows the force is a power law (log-log interpolation), below the first row the first segment's
power law: exactly what the engine looks up (laws.tables). `damping.csv` holds the Hunt-Crossley
factor chi against the impact speed v0 (CHI_POINTS speeds even in ln v0 over the FE impacts'
range for damping "calibrated", held at the ends; one row for a constant chi), so that

    F(d, d') = max(F_el(d) (1 + chi(v0) d' / v0), 0),  d > 0,

v0 the approach rate at the contact's onset, at least SPEED_FLOOR (m/s). `export.json` names
the joint, the laws, the damping, the units and the validity (the FE approaches, clearances and
impact speeds the laws were fitted over). `--to exudyn` adds `pinbore_exudyn.py`, which reads
those files and adds the clearance joint to an Exudyn system (a connector whose user function
is this force). The force of every row is pinbore.laws.contact.ContactLaw's: the functions the
multibody model runs.
"""

import csv
import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np

from pinbore.core.errors import InputError
from pinbore.laws import contact, lawsfile
from pinbore.reduced.mechanism import kinds
from pinbore.reduced.mechanism.layout import CHI_POINTS
from pinbore.reduced.mechanism.scene import clearance_joints

ADAPTER = Path(__file__).with_name("exudyn_adapter.py")


def selected(laws_data, laws_path: str, scene_path: str | None, joint_name: str | None,
             law_name: str | None) -> list[tuple]:
    """The laws to export as (law, joint, damping, restitution), checked against the file
    before any compiled law is loaded: a mechanism scene's clearance joint (its radii,
    materials, length, damping and calibrated normal law) or the one joint of the file's
    curves (every fitted law, or `law_name`)."""
    fitted = laws_data.fitted()
    if not fitted:
        raise InputError(f"{laws_path}: laws: the file has no fitted law to export (run pinbore "
                         "calibrate on curves that fix one)")
    if law_name is not None and law_name not in fitted:
        raise InputError(f"{laws_path}: --law: {law_name!r} is not a fitted law of the file; "
                         f"valid: {', '.join(fitted) or 'none'}")
    if scene_path is None:
        if joint_name is not None:
            raise InputError("--joint: names a clearance joint of --scene, which is missing")
        try:
            joint = lawsfile.curves_joint(
                laws_data, laws_path, "name a mechanism scene's joint: --scene SCENE [--joint NAME]")
        except ValueError as err:
            raise InputError(str(err)) from None
        return [(name, joint, None, None) for name in ([law_name] if law_name else fitted)]
    scene = kinds.load(scene_path)
    if kinds.of_scene(scene).dimension != 2:
        raise InputError(f"{scene_path}: --scene: a planar mechanism (kind = \"planar\"): the "
                         "tables are a revolute joint's force F = L P(d), a pin without tilt")
    joints = {c.name: c for c in clearance_joints(scene) if hasattr(c, "elastic_joint")}
    if joint_name is None and len(joints) == 1:
        joint_name = next(iter(joints))
    if joint_name not in joints:
        raise InputError(f"{scene_path}: --joint: {joint_name!r} is not a revolute clearance joint "
                         f"of the scene; valid: {', '.join(joints) or 'none'}")
    c = joints[joint_name]
    if law_name is None:
        law_name = c.normal_law.split(":", 1)[1] if c.normal_law.startswith("calibrated:") else None
        if law_name not in fitted:
            raise InputError(f"{scene_path}: clearance_joints.{joint_name}.normal_law: "
                             f"{c.normal_law!r} is not a fitted law of {laws_path}; name one "
                             "with --law")
    if c.length is None:   # every law of the file is a force per unit length
        raise InputError(f"{scene_path}: clearance_joints.{joint_name}.length: the joint needs its "
                         f"axial length (m) for the per-length law {law_name!r} (F = L P(d))")
    damping = c.damping_law if c.impact == "continuous" else "none"
    return [(law_name, c.elastic_joint(), damping, c.restitution)]


def force_table(law) -> np.ndarray:
    """Rows (approach d (m), elastic force F (N)) of a ContactLaw on the multibody model's
    grid, up to the last finite force (a law without a solution beyond)."""
    from pinbore.laws.tables import log_grid   # noqa: PLC0415 (compiled: after the checks)
    from pinbore.reduced.mechanism.joints.base import BLOW_UP_FRACTION  # noqa: PLC0415
    from pinbore.reduced.mechanism.model import GRID_LOW, GRID_POINTS  # noqa: PLC0415

    _, _, deltas = log_grid(GRID_LOW, BLOW_UP_FRACTION * law.joint.r_pin, GRID_POINTS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the validity is stated in export.json
        force = law.elastic(deltas)
    finite = np.isfinite(force) & (force > 0)
    last = int(np.argmin(finite)) if not finite.all() else deltas.size
    return np.column_stack([deltas[:last], force[:last]])


def damping_table(law) -> np.ndarray:
    """Rows (impact speed v0 (m/s), chi, e): CHI_POINTS speeds even in ln v0 over the FE
    impacts' speeds for calibrated damping, else one row (chi constant)."""
    if law.damping != "calibrated":
        return np.array([[1.0, law.chi(1.0), law.restitution_at(1.0)]])
    low, high = law.restitution_law.speed_range_m_per_s
    speeds = np.exp(np.linspace(math.log(low), math.log(high), CHI_POINTS))
    return np.array([[v, law.chi(v), law.restitution_at(v)] for v in speeds])


def _write_csv(path: Path, header: list[str], rows) -> None:
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows([[repr(float(x)) for x in row] for row in rows])


def description(laws: list) -> dict:
    """export.json: the joint, each law's table file and validity, the damping."""
    first = laws[0]
    j = first.joint
    return {
        "units": {"approach": "m", "force": "N", "speed": "m/s"},
        "force_model": "F(d, d') = max(F_el(d) (1 + chi(v0) d'/v0), 0) for d > 0, else 0; "
                       "F_el: log-log interpolation of the law's table (below its first row: the "
                       "first segment's power law; undefined beyond its last row); chi: linear in "
                       "ln v0 between the rows of damping.csv, held at its ends; v0: the approach "
                       "rate at the contact's onset, at least speed_floor_m_per_s",
        "speed_floor_m_per_s": speed_floor(),
        "joint": {"bearing_radius_m": j.r_bore, "journal_radius_m": j.r_pin,
                  "clearance_m": j.clearance, "length_m": j.length, "bearing_E_Pa": j.E_bore,
                  "bearing_nu": j.nu_bore, "journal_E_Pa": j.E_pin, "journal_nu": j.nu_pin},
        "damping": {"law": first.damping, "restitution": first.restitution,
                    "table": "damping.csv",
                    "speed_range_m_per_s": (list(first.restitution_law.speed_range_m_per_s)
                                            if first.restitution_law is not None else None)},
        "laws": {law.name.split(":", 1)[1]: {
            "table": f"{law.name.split(':', 1)[1]}.csv",
            "formula": law.laws_data.laws[law.name.split(":", 1)[1]].formula,
            "fitted_approach_m": list(law.approach_range_m),
            "fitted_clearance_m": list(law.clearance_range_m)} for law in laws},
    }


def speed_floor() -> float:
    """The smallest impact speed v0 (m/s) the multibody model's damping divides by."""
    from pinbore.reduced.mechanism.model import SPEED_FLOOR   # noqa: PLC0415

    return SPEED_FLOOR


def run(laws_path: str, to: str, out, scene_path=None, joint_name=None, law_name=None) -> int:
    from pinbore.core.output import atomic_directory   # noqa: PLC0415

    laws_data = lawsfile.read(Path(laws_path), laws_path)
    chosen = selected(laws_data, laws_path, scene_path, joint_name, law_name)
    try:
        laws = [contact.law_of(laws_data, *row, source=scene_path or laws_path) for row in chosen]
    except ValueError as err:
        raise InputError(str(err)) from None
    tables = [force_table(law) for law in laws]
    for law, table in zip(laws, tables):
        if table.shape[0] < 2:   # a table needs two rows to interpolate
            raise InputError(f"{laws_path}: laws.{law.name.split(':', 1)[1]}: the law gives no "
                             "finite, positive force on the multibody model's approaches: nothing "
                             "to export")
    with atomic_directory(out) as tmp:
        for law, table in zip(laws, tables):
            _write_csv(tmp / f"{law.name.split(':', 1)[1]}.csv", ["approach_m", "force_N"], table)
        _write_csv(tmp / "damping.csv", ["impact_speed_m_per_s", "chi", "restitution"],
                   damping_table(laws[0]))
        (tmp / "export.json").write_text(json.dumps(description(laws), indent=2) + "\n")
        if to == "exudyn":
            shutil.copyfile(ADAPTER, tmp / "pinbore_exudyn.py")
    return 0
