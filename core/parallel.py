"""Tasks run in parallel and cached point by point: the runner under the sweep engine
(core.sweep) of every sweep and study (`pinbore dynamics` sweeps, `pinbore study`).

`cached_map(task, items, names, cache, workers, scheduler)` calls `task(item)` for every item
whose result is not yet in `cache` (one JSON file per item, named by `names`), in parallel: on
local processes (a pool of `workers` long-lived processes: each imports the code once, then
runs point after point in process), or on a Dask cluster (`scheduler`: its
address, through the client's executor). Each result is written atomically (a temporary file
renamed into place) as soon as it arrives, so a run stopped in any way, SIGKILL included,
resumes with every finished point kept and none computed twice; the points under way when it
stopped are computed again. Items of one name are computed once.

The rules of the options (`default_workers`, `check_scheduler`, `check_workers`,
`check_cache`) are here too, for the options model of the sweep engine (core.sweep.Runner).
"""

import concurrent.futures
import contextlib
import hashlib
import importlib.util
import json
import multiprocessing
import os
import re
import signal
import socket
import time
from pathlib import Path

from tqdm import tqdm

from pinbore.core.errors import InputError

SCHEDULER_TIMEOUT = 10   # s to connect to a Dask scheduler
TCP = re.compile(r"(?:tcp://)?\[?([A-Za-z0-9_.:-]+?)\]?:([0-9]{1,5})/?")   # a TCP address: host, port
ADDRESS = re.compile(r"[a-z][a-z0-9+.-]*://\S+|[A-Za-z0-9_.\[\]:-]+:[0-9]{1,5}")   # protocol://..., host:port
WORKERS_PER_CORE = 4
STOP_GRACE = 2.0   # s a stopped run's workers have to unwind their points before they are killed
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
        from pinbore.core.output import signals_held   # noqa: PLC0415

        with executor(workers, scheduler, len(todo)) as pool:   # before the cache exists: a scheduler
            cache.mkdir(parents=True, exist_ok=True)  # that cannot be reached leaves nothing
            with signals_held():   # each worker started whole, so that a stop finds it
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


_in_point = False   # a local worker runs a point (_point)


def _worker_started() -> None:
    """A local worker's signals: Ctrl-C, which reaches the whole process group, is the
    parent's to handle (it stops the workers, below; a worker prints nothing of it); SIGTERM, the parent's stop, unwinds the point under way (its
    temporary folders removed, `_point`) or, between points, ends the worker at once. The
    parent held both off while it started the worker (cached_map), which inherits that: let
    them through (one that came meanwhile is handled now)."""
    from pinbore.core.output import STOPS, Terminated   # noqa: PLC0415

    def stop(signum, frame):
        if _in_point:
            raise Terminated
        os._exit(128 + signum)

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, stop)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOPS)


def _point(task, item):
    """task(item) in a local worker; a worker stopped in it ends once the point has unwound."""
    global _in_point
    from pinbore.core.output import Terminated   # noqa: PLC0415

    _in_point = True
    try:
        return task(item)
    except (Terminated, KeyboardInterrupt):
        os._exit(128 + signal.SIGTERM)
    finally:
        _in_point = False


def _stop_workers(processes) -> None:
    """End a stopped run's local workers now rather than after the points under way: SIGTERM
    (each unwinds its point), then SIGKILL for one still running after STOP_GRACE s."""
    for p in processes:
        if p.is_alive():
            p.terminate()
    deadline = time.monotonic() + STOP_GRACE
    for p in processes:
        p.join(max(0.0, deadline - time.monotonic()))
        if p.is_alive():
            p.kill()
            p.join()


class _Local:
    """A pool of local processes whose submit runs each task through `_point`."""

    def __init__(self, pool):
        self.pool = pool

    def submit(self, task, item):
        return self.pool.submit(_point, task, item)


@contextlib.contextmanager
def executor(workers: int, scheduler: str | None, pending: int | None = None):
    """An executor of local processes or of a Dask cluster for the block. A stop (Ctrl-C,
    SIGTERM, an error) cancels the points not yet started instead of waiting for them and
    ends the local workers' points under way (their temporary folders removed); the Dask
    client is closed. An unreachable scheduler is one InputError line."""
    if scheduler is None:
        # spawned, not forked: the parent runs threads (tqdm, BLAS) that fork would copy mid-state
        pool = concurrent.futures.ProcessPoolExecutor(
            max_workers=max(1, min(workers, pending or workers)),
            mp_context=multiprocessing.get_context("spawn"), initializer=_worker_started)
        try:
            yield _Local(pool)
        except BaseException:
            # (the pool's processes: no public handle before Python 3.14's terminate_workers;
            # shutdown forgets them)
            processes = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            _stop_workers(processes)
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
