"""The one sweep engine: the points of `pinbore study` and of the sweeps of `pinbore dynamics`,
each a scene's data with some of its keys set, run in parallel and cached by their content.

- A key of a scene is dotted: its parts are the tables and the list items (by index) on the
  way, `clearance_joints.0.journal_radius`, `drive.speed_rpm`. `put` sets one, `get` reads one.
- A point's cache entry is named by its content (`point_keys`): the SHA-256 of the kind of its
  run, its whole scene, the contents of the files the points name (`digest_files` of
  `named_files`), the hash of the code that runs it (core.codedeps) and the settings that
  change its result. Two ways of naming one scene (a dotted key, a command's shorthand for it)
  ask for one entry, so a rerun runs only new or changed points and a stopped run resumes.
- `Runner` is the model of the options of a command whose points run here, with their rules
  (core.parallel): --out, --scheduler, --workers, --cache (default OUT-cache). The options
  models of the commands derive from it.
- `run` runs the points not yet cached on local processes or a Dask cluster
  (core.parallel.cached_map).
"""

import hashlib
import json
from pathlib import Path

import pydantic

from pinbore.core import scene as scenes
from pinbore.core.parallel import cached_map, check_cache, check_scheduler, check_workers, default_workers
from pinbore.core.scene import Strict

ABSENT = "no such key in the base scene"


def put(data: dict, key: str, value, create: bool = False, absent: str = ABSENT) -> None:
    """Set a dotted key of a scene's data in place (list items by index). KeyError naming the
    part of the key that is not in the scene (`absent` says so; `create`: the last part may be
    new, and tables on the way are made). Without `create` the key must hold a number, and a
    whole value put where an integer stands stays an integer (a count: modes, slices)."""
    parts = key.split(".")
    node = data
    for i, part in enumerate(parts):
        last = i == len(parts) - 1
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise KeyError(f"{'.'.join(parts[:i + 1])}: no such item (the list has {len(node)})")
            part = int(part)
        elif not isinstance(node, dict):
            raise KeyError(f"{'.'.join(parts[:i])}: holds a value, not a table")
        elif part not in node:
            if not create:
                raise KeyError(f"{'.'.join(parts[:i + 1])}: {absent}")
            node[part] = value if last else {}
        if last:
            if not create and (not isinstance(node[part], (int, float)) or isinstance(node[part], bool)):
                raise KeyError(f"{key}: not a number in the base scene")
            if not create and isinstance(node[part], int) and float(value).is_integer():
                value = int(value)
            node[part] = value
        else:
            node = node[part]


def get(data: dict, key: str):
    """A dotted key of a scene's data or of a point's result (list items by index); KeyError
    when absent."""
    node = data
    for part in key.split("."):
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict) and part in node:
            node = node[part]
        else:
            raise KeyError(key)
    return node


def named_files(points, base: Path) -> list[Path]:
    """Every file the points' scenes name (core.scene.named_files), relative names taken from
    `base`, once each: what the points read, and what their keys cover."""
    return sorted({f for data in points for f in scenes.named_files(data, base)})


def digest_files(paths) -> list[str]:
    """SHA-256 of each file a scene names (its laws file ...); the name of one that is not
    there."""
    return [hashlib.sha256(Path(p).read_bytes()).hexdigest() if Path(p).is_file() else str(p)
            for p in paths]


def point_keys(kind: str, points, files: list[str], code: str, *settings) -> list[str]:
    """The cache key of each point: the SHA-256 of its kind, its whole scene data, the files'
    digests (digest_files), the code hash (core.codedeps) and the settings that change its
    result (JSON-able)."""
    return [hashlib.sha256(json.dumps([kind, data, files, code, *settings], sort_keys=True).encode()).hexdigest()
            for data in points]


class Runner(Strict):
    """The options of a command whose points run through the engine: the output directory, the
    Dask cluster at `scheduler` or `workers` local processes (default: the cores), and the
    folder of the points' cache entries (default OUT-cache, beside the outputs). Rules:
    --workers a whole number >= 1, local processes only, at most WORKERS_PER_CORE a core;
    --scheduler an address, with the dask `distributed` package installed; --cache no file,
    outside OUT, holding nothing but cache entries (core.parallel)."""

    out: Path = pydantic.Field(description="the output directory")
    scheduler: str | None = None
    workers: int = pydantic.Field(default_factory=default_workers)
    cache: Path

    @pydantic.model_validator(mode="before")
    @classmethod
    def _default_cache(cls, data):
        if isinstance(data, dict) and data.get("cache") is None and data.get("out") is not None:
            return data | {"cache": Path(f"{data['out']}-cache")}
        return data

    @pydantic.field_validator("scheduler")
    @classmethod
    def _cluster(cls, address: str | None) -> str | None:
        return check_scheduler(address)

    @pydantic.field_validator("workers")
    @classmethod
    def _local(cls, workers: int, info: pydantic.ValidationInfo) -> int:
        """Local processes only (a field validator runs on given values, not on the default)."""
        if workers < 1:
            raise ValueError(f"at least 1 (got {workers})")
        return check_workers(workers, info.data.get("scheduler"))

    @pydantic.field_validator("cache")
    @classmethod
    def _cache_folder(cls, folder: Path, info: pydantic.ValidationInfo) -> Path:
        return check_cache(folder, info.data.get("out"))


def run(task, items, keys: list[str], options: Runner, desc: str = "sweep") -> tuple[list, list[bool]]:
    """task(item) for every item whose key has no entry in options.cache, in parallel where the
    options say; the results in the order of `items`, and per item whether it ran now (False:
    read from the cache). Items of one key run once."""
    return cached_map(task, items, keys, options.cache, options.workers, options.scheduler, desc)
