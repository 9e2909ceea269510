"""The parameter a `pinbore dynamics` sweep or continuation varies: a dotted key of the scene
(core.sweep.put: `drive.speed_rpm`, `clearance_joints.0.friction.mu`, `loads.0.frequency_hz`,
`integrator.rtol`; any number of the validated scene, its defaults included), or a shorthand
of PARAMETERS, each defined once by the dotted keys it sets at a value:

- clearance (m, > 0): every clearance joint's radial clearance,
  `clearance_joints.<i>.journal_radius` = its bearing_radius - value and
  `translational_joints.<i>.clearance` = value;
- speed (rpm, > 0): `drive.speed_rpm`;
- friction (mu, >= 0): `clearance_joints.<i>.friction.mu` of every clearance joint;
- frequency (Hz, > 0): the forcing's fundamental, every `loads.<i>.frequency_hz` and
  `drive.harmonics.<i>.frequency_hz` in proportion;
- amplitude (a factor, > 0): every excitation amplitude times the value, `loads.<i>.force.<k>`,
  `loads.<i>.torque` and `drive.harmonics.<i>.amplitude_deg` (1: the scene's).

A shorthand keeps its physical bound on a swept range; a dotted key is bound by the scene's
own rules, checked at both ends of the range (pinbore.reduced.dynamics.studies.check_scene).
"""

import copy
import re
from typing import Callable, NamedTuple

from pinbore.core.errors import InputError
from pinbore.core.sweep import get, put

DOTTED = re.compile(r"[A-Za-z0-9_]+(\.[A-Za-z0-9_]+)*")   # a dotted key: names and indices
SCENE_UNITS = "the scene's units"   # the axis label of a dotted key's values


def _clearance(data: dict, value: float, source: str) -> dict:
    joints, sliders = data.get("clearance_joints", []), data.get("translational_joints", [])
    if not joints and not sliders:
        raise InputError(f"{source}: --parameter clearance: the scene has no clearance joints")
    return {**{f"clearance_joints.{i}.journal_radius": j["bearing_radius"] - value for i, j in enumerate(joints)},
            **{f"translational_joints.{i}.clearance": value for i in range(len(sliders))}}


def _speed(data: dict, value: float, source: str) -> dict:
    if (data.get("drive") or {}).get("speed_rpm") is None:
        raise InputError(f"{source}: --parameter speed: the scene has no drive turning at constant speed")
    return {"drive.speed_rpm": value}


def _friction(data: dict, value: float, source: str) -> dict:
    joints = data.get("clearance_joints", [])
    if not joints or any("mu" not in (j.get("friction") or {}) for j in joints):
        raise InputError(f"{source}: --parameter friction: every clearance joint needs a friction law "
                         "with a coefficient mu (coulomb_ambrosio, dahl, iwan_bilinear)")
    return {f"clearance_joints.{i}.friction.mu": value for i in range(len(joints))}


def _excitations(data: dict, parameter: str, source: str) -> list[tuple[str, dict]]:
    """(dotted key, table) of every harmonic load and of every harmonic of a shaken drive."""
    found = [(f"loads.{i}", e) for i, e in enumerate(data.get("loads", []))]
    found += [(f"drive.harmonics.{i}", h) for i, h in enumerate((data.get("drive") or {}).get("harmonics", []))]
    if not found:
        raise InputError(f"{source}: --parameter {parameter}: the scene has no harmonic loads or shaken "
                         "drive (drive.harmonics)")
    return found


def _frequency(data: dict, value: float, source: str) -> dict:
    excitations = _excitations(data, "frequency", source)
    if (data.get("drive") or {}).get("speed_rpm") is not None:
        raise InputError(f"{source}: --parameter frequency: the drive turns at constant speed and sets "
                         "the period; continue in speed instead")
    ratio = value / min(e["frequency_hz"] for _, e in excitations)
    return {f"{key}.frequency_hz": e["frequency_hz"] * ratio for key, e in excitations}


def _amplitude(data: dict, value: float, source: str) -> dict:
    keys = {}
    for key, e in _excitations(data, "amplitude", source):
        if key.startswith("drive."):
            keys[f"{key}.amplitude_deg"] = e["amplitude_deg"] * value
        for name in ("force", "torque"):
            if isinstance(e.get(name), list):
                keys |= {f"{key}.{name}.{k}": value * f for k, f in enumerate(e[name])}
            elif name in e:
                keys[f"{key}.{name}"] = value * e[name]
    return keys


def _own_clearance(scene) -> float:
    from pinbore.reduced.mechanism.scene import clearance_joints   # noqa: PLC0415

    return clearance_joints(scene)[0].gap()


class Shorthand(NamedTuple):
    """A named parameter: its axis label (unit, meaning), whether a value must be > 0 (a size,
    a speed) or only >= 0, the dotted keys it sets at a value (keys(data, value, source) ->
    {key: value}; one InputError line when the scene has nothing it sets) and the scene's own
    value (own(scene), where a continuation starts)."""

    label: str
    positive: bool
    keys: Callable[[dict, float, str], dict]
    own: Callable[[object], float]


PARAMETERS = {
    "clearance": Shorthand("m, radial clearance of every clearance joint", True, _clearance, _own_clearance),
    "speed": Shorthand("rpm, the drive's speed", True, _speed, lambda scene: scene.drive.speed_rpm),
    "friction": Shorthand("mu of every clearance joint's friction law", False, _friction,
                          lambda scene: scene.clearance_joints[0].friction.mu),
    "frequency": Shorthand("Hz, the forcing's fundamental (every harmonic in proportion)", True, _frequency,
                           lambda scene: 1.0 / scene.forcing_period()),
    "amplitude": Shorthand("x, a factor on every excitation amplitude (1: the scene's)", True, _amplitude,
                           lambda scene: 1.0),
}
NAMES = ", ".join(PARAMETERS)


def check_name(parameter: str) -> str:
    """A shorthand or a dotted key's form (whether the scene has the key is checked on it)."""
    if parameter not in PARAMETERS and not DOTTED.fullmatch(parameter):
        raise ValueError(f"{parameter!r} must be a dotted key of the scene (e.g. drive.speed_rpm) or one "
                         f"of {NAMES}")
    return parameter


def label(parameter: str) -> str:
    """The unit and meaning of a parameter's values, for an axis."""
    return PARAMETERS[parameter].label if parameter in PARAMETERS else SCENE_UNITS


def settings(data: dict, parameter: str, value: float, source: str) -> dict:
    """The dotted keys that setting `parameter` to `value` sets in the scene's data, with their
    values: a shorthand's, or the key itself."""
    shorthand = PARAMETERS.get(parameter)
    return shorthand.keys(data, value, source) if shorthand else {parameter: value}


def with_parameter(data: dict, parameter: str, value: float, source: str) -> dict:
    """A copy of the scene's data with `parameter` set to `value` (core.sweep.put of every key
    it sets); a key the scene does not have is one InputError line naming it."""
    data = copy.deepcopy(data)
    for key, setting in settings(data, parameter, value, source).items():
        try:
            put(data, key, setting, absent=f"no such key in the scene (--parameter takes a dotted key "
                                           f"of the scene or one of {NAMES})")
        except KeyError as err:   # the key named once when it is the parameter itself
            reason = err.args[0].removeprefix(f"{parameter}: ")
            raise InputError(f"{source}: --parameter {parameter}: {reason}") from None
    return data


def parameter_value(scene, data: dict, parameter: str) -> float:
    """The scene's own value of a parameter (where a continuation starts): a shorthand's own,
    or the number the scene's data holds at the key."""
    shorthand = PARAMETERS.get(parameter)
    return shorthand.own(scene) if shorthand else float(get(data, parameter))


def physical(parameter: str, low: float) -> None:
    """ValueError unless `low`, the smallest value of a shorthand's range, is within its bound
    (> 0 or >= 0); a dotted key's values are bound by the scene's rules."""
    shorthand = PARAMETERS.get(parameter)
    if shorthand is not None and (low < 0 or (shorthand.positive and low == 0)):
        raise ValueError(f"{parameter} must be {'>' if shorthand.positive else '>='} 0 (got LOW {low:g})")
