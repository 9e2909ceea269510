"""Reading scene files: TOML in SI units, validated into typed models; and the JSON files
one stage writes for the next, read back through the same kind of model.

Every scene model derives from `Strict`: unknown keys are errors, missing keys are errors,
and a broken rule is reported as one line `<file>: <key>: <rule>`.
"""

import contextlib
import json
import tempfile
import tomllib
import warnings
from pathlib import Path
from typing import Annotated

import pydantic

from pinbore.core.errors import InputError

# What a stage's file that does not read as its model most likely is, and the remedy.
RUN_AGAIN = "written by another version of pinbore? run pinbore {command} again"
# a scene kind's former name -> the kind's name, still read (normal_kind)
RENAMED_KINDS = {"reduced": "planar"}


class Strict(pydantic.BaseModel):
    """Base of every scene table: no unknown keys, no silent type coercion, immutable, and
    every number finite (inf and nan are refused wherever a float is read)."""

    model_config = pydantic.ConfigDict(extra="forbid", strict=True, frozen=True,
                                       allow_inf_nan=False)


# a physical value of a Record that must be a positive number (a Record's numbers may otherwise
# be inf or nan, which a run that blew up honestly records)
Positive = Annotated[float, pydantic.Field(gt=0, allow_inf_nan=False)]


class Record(Strict):
    """Base of the files pinbore writes between stages (laws.json, summary.json): strict keys
    like a scene, but a number may be inf or nan, which is what a run that blew up or a law
    without a solution honestly records."""

    model_config = pydantic.ConfigDict(allow_inf_nan=True)


def read_toml(path: str | Path) -> dict:
    """The parsed TOML file, or an InputError naming the file and the problem."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise InputError(f"{path}: cannot read scene file ({err.strerror})") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a text file (a scene is TOML in UTF-8)") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"{path}: not valid TOML ({err})") from None


def validate(model: type[pydantic.BaseModel], data: dict, source: str) -> pydantic.BaseModel:
    """`model` built from `data`; the first validation error becomes one InputError line."""
    try:
        return model.model_validate(data)
    except pydantic.ValidationError as err:
        first = err.errors()[0]
        key = ".".join(str(part) for part in first["loc"]) or "(scene)"
        raise InputError(f"{source}: {key}: {_rule(first)}") from None


def _rule(error: dict) -> str:
    """Pydantic's message, phrased as the rule that was broken."""
    kind = error["type"]
    if kind == "missing":
        return "required key is missing"
    if kind == "extra_forbidden":
        return "unknown key"
    bound = {"greater_than": "gt", "greater_than_equal": "ge", "less_than": "lt",
             "less_than_equal": "le"}.get(kind)
    if bound is not None and isinstance(error.get("ctx", {}).get(bound), (int, float)):
        # the bound as a number reads (1e-08, not pydantic's 0.00000001)
        return f"{error['msg'].rsplit(' ', 1)[0]} {error['ctx'][bound]:g}"
    message = error["msg"]
    return message.removeprefix("Value error, ")


def referenced_files(path: str | Path) -> list[Path]:
    """The files a scene file names (named_files), relative to its folder unless absolute. A
    scene that cannot be read names none (reading it for its run says why)."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
        return []
    return named_files(data, path.parent)


def _map_files(node, f):
    """Scene data with f applied to every file it names: the string value of a key `*_file`
    and each string of a list `*_files`, in any table (tables in lists included)."""
    if isinstance(node, dict):
        out = {}
        for key, value in node.items():
            if key.endswith("_file") and isinstance(value, str):
                out[key] = f(value)
            elif key.endswith("_files") and isinstance(value, list):
                out[key] = [f(v) if isinstance(v, str) else v for v in value]
            else:
                out[key] = _map_files(value, f)
        return out
    if isinstance(node, list):
        return [_map_files(v, f) for v in node]
    return node


def named_file(name, base) -> Path:
    """A file a scene names: relative to the scene's folder `base` unless absolute."""
    path = Path(name)
    return path if path.is_absolute() else Path(base) / path


def named_files(data, base: Path) -> list[Path]:
    """The files scene data names (_map_files), relative to `base` unless absolute."""
    found = []
    _map_files(data, lambda name: found.append(name) or name)
    return [named_file(f, base) for f in found]


def absolute_files(data, base: Path):
    """A copy of scene data with the files it names made absolute against `base` (what a
    scene file's names are against its folder; a relative base is taken from the working
    directory)."""
    return _map_files(data, lambda name: str((Path(base) / name).absolute()))


def normal_kind(data: dict, source: str) -> dict:
    """Scene data whose `kind` is a former name (RENAMED_KINDS) as a copy of it with the
    kind's name, and a FutureWarning naming the file, the key and the name to write (shown
    once per file and process); other data as it is. Every reader of a scene's kind reads it
    through here."""
    kind = data.get("kind")
    if not isinstance(kind, str) or kind not in RENAMED_KINDS:
        return data
    warnings.warn(f'{source}: kind: "{kind}" is deprecated: write kind = "{RENAMED_KINDS[kind]}"',
                  FutureWarning, stacklevel=1)   # one location: the same file warns once
    return data | {"kind": RENAMED_KINDS[kind]}


def _toml_ready(node, where: str = "") -> None:
    """Scene data that TOML can hold: string keys, no None (TOML has no null: leave the key
    out); InputError naming the key."""
    if isinstance(node, dict):
        for key, value in node.items():
            if not isinstance(key, str):
                raise InputError(f"scene: {where + ': ' if where else ''}the key {key!r} must be a string")
            _toml_ready(value, f"{where}.{key}" if where else key)
    elif isinstance(node, (list, tuple)):
        for k, value in enumerate(node):
            _toml_ready(value, f"{where}.{k}")
    elif node is None:
        raise InputError(f"scene: {where}: None is no TOML value (leave the key out for its default)")


def write_scene(path: str | Path, data: dict, base) -> Path:
    """Write scene data as a TOML scene file at `path`, the files it names made absolute
    against `base` (absolute_files: where the data's relative names are taken from); its path.
    Data that TOML cannot hold is one InputError line naming the key."""
    import tomli_w   # noqa: PLC0415

    _toml_ready(data)
    path = Path(path)
    path.write_text(tomli_w.dumps(absolute_files(data, base)), encoding="utf-8")
    return path


@contextlib.contextmanager
def scene_file(data: dict, base, name: str = "scene"):
    """Scene data as a scene file for the block (write_scene, in a temporary folder removed
    after it, which the block may also write its outputs to); an InputError of the block
    names the data, `name`, not that file."""
    with tempfile.TemporaryDirectory(prefix="pinbore-scene-") as folder:
        path = write_scene(Path(folder) / "scene.toml", data, base)
        try:
            yield path
        except InputError as err:
            raise InputError(str(err).replace(str(path), name)) from None


def load(model: type[pydantic.BaseModel], path: str | Path) -> pydantic.BaseModel:
    """Read and validate a scene file."""
    return validate(model, read_toml(path), str(path))


def load_json(path: str | Path, command: str, source: str | None = None) -> dict:
    """The JSON object of a file that `pinbore <command>` wrote. A file that cannot be read or
    parsed, or holds no object, is one InputError line naming it (`source`, default: its
    path)."""
    source = str(path) if source is None else source
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError) as err:
        raise InputError(f"{source}: cannot read ({getattr(err, 'strerror', None) or err})") from None
    if not isinstance(data, dict):
        raise InputError(f"{source}: not a JSON object ({RUN_AGAIN.format(command=command)})")
    return data


def read_json(model: type[pydantic.BaseModel], path: str | Path, command: str,
              source: str | None = None) -> pydantic.BaseModel:
    """A JSON file that `pinbore <command>` wrote, validated into `model`. A file that cannot
    be read, parsed or validated is one InputError line: `<source>: <key>: <rule>`, the rule
    followed by RUN_AGAIN; `source` names the file (default: its path)."""
    source = str(path) if source is None else source
    data = load_json(path, command, source)
    try:
        return validate(model, data, source)
    except InputError as err:
        raise InputError(f"{err} ({RUN_AGAIN.format(command=command)})") from None
