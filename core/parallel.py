"""Tasks run in parallel and cached point by point: the one runner of every sweep and study
(`pinbore dynamics` sweeps, `pinbore study`).

`cached_map(task, items, names, cache, workers, scheduler)` calls `task(item)` for every item
whose result is not yet in `cache` (one JSON file per item, named by `names`), in parallel: on
local processes (a pool of `workers` long-lived processes: each imports the code once, then
runs point after point in process), or on a Dask cluster (`scheduler`: its
address, through the client's executor). Each result is written atomically (a temporary file
renamed into place) as soon as it arrives, so a run stopped in any way, SIGKILL included,
resumes with every finished point kept and none computed twice; the points under way when it
stopped are computed again. Items of one name are computed once.

The rules of the options (`default_workers`, `check_scheduler`, `check_workers`,
`check_cache`) are here too, for the options models of the commands to share.
"""

import concurrent.futures
import contextlib
import hashlib
import importlib.util
import json
import multiprocessing
import os
import re
import socket
from pathlib import Path

from tqdm import tqdm

from pinbore.core.errors import InputError

SCHEDULER_TIMEOUT = 10   # s to connect to a Dask scheduler
TCP = re.compile(r"(?:tcp://)?\[?([A-Za-z0-9_.:-]+?)\]?:([0-9]{1,5})/?")   # a TCP address: host, port
ADDRESS = re.compile(r"[a-z][a-z0-9+.-]*://\S+|[A-Za-z0-9_.\[\]:-]+:[0-9]{1,5}")   # protocol://..., host:port
WORKERS_PER_CORE = 4
ENTRY = re.compile(r"\..*|.*\.json")   # a cache's files: entries (and hidden ones: entries being written, .gitignore)


def default_workers() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def check_scheduler(address: str | None) -> str | None:
    """A Dask scheduler's address (None: local processes), protocol://host[:port] or
    host:port; ValueError naming the rule."""
    if address is None:
        return None
    if not ADDRESS.fullmatch(address.strip()):
        raise ValueError(f"{address!r} must be a scheduler's address, protocol://host[:port] "
                         "or host:port, e.g. tcp://host:8786")
    if importlib.util.find_spec("distributed") is None:
        raise ValueError("needs the dask 'distributed' package")
    return address


def check_workers(workers: int, scheduler: str | None) -> int:
    """Local processes go with no scheduler (the cluster has its own workers), at most
    WORKERS_PER_CORE a core (more only queue for the cores, each a process of its own)."""
    if scheduler is not None:
        raise ValueError("not used with --scheduler (the cluster has its own workers)")
    most = WORKERS_PER_CORE * default_workers()
    if workers > most:
        raise ValueError(f"{workers} is more than {most} ({WORKERS_PER_CORE} a core of the "
                         f"{default_workers()} this run may use): more processes only wait for them")
    return workers


def check_cache(folder: Path, out: Path | None) -> Path:
    """A cache folder: no existing file, nor inside one; outside the output directory (which
    a run replaces whole when it completes); and, if it exists, holding nothing but cache
    entries (a folder of other files is not a cache to write into)."""
    if folder.exists() and not folder.is_dir():
        raise ValueError(f"{folder} is an existing file, not a folder")
    inside = next((p for p in folder.absolute().parents if p.exists() and not p.is_dir()), None)
    if inside is not None:
        raise ValueError(f"{folder} lies inside {inside}, which is a file")
    if out is not None and (folder.resolve() == out.resolve() or out.resolve() in folder.resolve().parents):
        raise ValueError(f"{folder} lies in --out {out}, which is replaced when the run completes")
    if folder.is_dir():
        foreign = next((p.name for p in folder.iterdir() if not ENTRY.fullmatch(p.name)), None)
        if foreign is not None:
            raise ValueError(f"{folder} holds {foreign}, which is not a cache entry: a folder of "
                             "other files is not a cache (name a new folder)")
    return folder


def sealed(result) -> str:
    """A cache entry: the result with the SHA-256 of its JSON, so that an entry edited or
    truncated is computed again, never served."""
    text = json.dumps(result, sort_keys=True)
    return json.dumps({"sha256": hashlib.sha256(text.encode()).hexdigest(), "result": result})


def unsealed(text: str):
    """The result of a cache entry whose checksum holds; ValueError otherwise."""
    entry = json.loads(text)
    if not isinstance(entry, dict) or set(entry) != {"sha256", "result"}:
        raise ValueError("not a cache entry")
    if hashlib.sha256(json.dumps(entry["result"], sort_keys=True).encode()).hexdigest() != entry["sha256"]:
        raise ValueError("its checksum does not hold")
    return entry["result"]


def cached_map(task, items, names, cache: Path, workers: int, scheduler: str | None,
               desc: str = "sweep") -> tuple[list, list[bool]]:
    """task(item) for every item, in parallel, each result cached as `cache/<name>.json`
    (JSON-able results, sealed with their checksum; a cached file that does not read or whose
    checksum does not hold is computed again). Returns the
    results in the order of `items` and, per item, whether it was computed by this call
    (False: read from the cache)."""
    names = list(names)
    results, todo = {}, {}
    for item, name in zip(items, names, strict=True):
        if name in results or name in todo:
            continue
        try:
            results[name] = unsealed((cache / f"{name}.json").read_text())
        except (OSError, ValueError):
            todo[name] = item
    done_before = set(results)
    if todo:
        with executor(workers, scheduler, len(todo)) as pool:   # before the cache exists: a scheduler
            cache.mkdir(parents=True, exist_ok=True)  # that cannot be reached leaves nothing
            futures = {pool.submit(task, item): name for name, item in todo.items()}
            for future in tqdm(concurrent.futures.as_completed(futures), total=len(futures),
                               desc=desc, unit="point", initial=len(done_before)):
                name = futures[future]
                result = future.result()
                tmp = cache / f".{name}.{os.getpid()}.json.tmp"
                tmp.write_text(sealed(result))
                tmp.rename(cache / f"{name}.json")
                results[name] = result
    return [results[n] for n in names], [n not in done_before for n in names]


def refused(scheduler: str) -> None:
    """One InputError line at once when nothing listens at a TCP scheduler's address (the
    connection is refused): Dask's client would retry until its timeout. Other protocols and
    addresses that do not answer are left to the client."""
    match = TCP.fullmatch(scheduler)
    if match is None:
        return
    try:
        socket.create_connection((match.group(1), int(match.group(2))), timeout=SCHEDULER_TIMEOUT).close()
    except ConnectionRefusedError:
        raise InputError(f"--scheduler {scheduler}: cannot reach the Dask scheduler: nothing listens "
                         "there (connection refused)") from None
    except OSError:
        return   # unreachable or slow: the client's own timeout says so


@contextlib.contextmanager
def executor(workers: int, scheduler: str | None, pending: int | None = None):
    """An executor of local processes or of a Dask cluster for the block. A stop (Ctrl-C,
    SIGTERM, an error) cancels the points not yet started instead of waiting for them; the
    Dask client is closed. An unreachable scheduler is one InputError line."""
    if scheduler is None:
        # spawned, not forked: the parent runs threads (tqdm, BLAS) that fork would copy mid-state
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=max(1, min(workers, pending or workers)),
            mp_context=multiprocessing.get_context("spawn"))
        try:
            yield pool
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown()
        return
    from distributed import Client   # noqa: PLC0415 (optional: check_scheduler checks it is there)
    refused(scheduler)
    try:
        client = Client(scheduler, timeout=SCHEDULER_TIMEOUT)
    except (OSError, TimeoutError) as err:
        raise InputError(f"--scheduler {scheduler}: cannot reach the Dask scheduler within "
                         f"{SCHEDULER_TIMEOUT} s ({type(err).__name__})") from None
    try:
        yield client.get_executor()
    finally:
        client.close()
