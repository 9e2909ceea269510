"""Outputs appear whole or not at all, and never at the cost of a user's files.

A run writes into a temporary sibling of its output directory and renames it into place only
when everything is written; a failed or interrupted run leaves the old directory (if any)
untouched and removes its temporary one. Under MPI, rank 0 owns the file system: it creates
the temporary directory, broadcasts its name, and renames it when the ranks agree that the
run succeeded.

What `--out` may be (`check_output`, applied before any work by `reserved` as it takes the
lock, and again by `atomic_directory` under it):
- a path that does not exist yet, or an empty directory;
- a directory that pinbore wrote itself (it holds the marker file `.pinbore-output`) and that
  holds none of the run's inputs, by the same command (the marker names it) or by one that
  did not say.
The run's inputs are what the command declared (`declared_inputs`: the CLI declares every
file each command reads, in one table) and what the stage itself passes; every check sees
both, so a stage cannot forget an input its command reads.
Refused, with one line naming the rule: `""` and `.`, the working directory or a folder
above it, a file, a directory that pinbore did not write and that is not empty, a path that
contains an input (the scene, the curves, a cache), a parent that is a file or cannot be
written. Two runs writing one `--out` at once: the second finds the lock (`flock` on
`.<name>.pinbore-lock` beside it) and refuses at once: a command holds its `--out`
(`reserved`) from before its work to its end, so that a second run is refused before it
computes anything, and SIGINT and SIGTERM stop the work cleanly wherever it is (what it
keeps in temporary folders removed as the stop unwinds). Temporary directories carry the writing
process's id; one left by a killed process (SIGKILL) is removed by the next run for the same
`--out`.
"""

import contextlib
import contextvars
import fcntl
import os
import re
import shutil
import signal
import sys
import tempfile
import threading
from pathlib import Path

from mpi4py import MPI

from pinbore.core.errors import InputError

_DECLARED: contextvars.ContextVar[tuple] = contextvars.ContextVar("declared_inputs", default=())
_RESERVED: contextvars.ContextVar[Path | None] = contextvars.ContextVar("reserved", default=None)
_COMMAND: contextvars.ContextVar[str | None] = contextvars.ContextVar("declared_command", default=None)

MARKER = ".pinbore-output"
MARKER_TEXT = "Written by pinbore. A later run with this --out replaces this directory whole.\n"


class Terminated(BaseException):
    """SIGTERM arrived during the command (raised where the process was)."""


STOPS = (signal.SIGINT, signal.SIGTERM)
_stopped: list[int] = []   # the signals that stopped the command (_stop)


def _stop(signum, frame):
    _stopped.append(signum)
    raise KeyboardInterrupt if signum == signal.SIGINT else Terminated


def _raise_if_stopped() -> None:
    """A stop swallowed by a library's callback, after which the library carried on: stop now."""
    if _stopped:
        _stop(_stopped.pop(), None)


_abandoned: list[bool] = []   # native work left running by a stop (a Gmsh mesher)


def abandon_native_work() -> None:
    """A stop left native work running in a thread (meshes.model.generate): the process must
    end without its native exit handlers (exit_now)."""
    _abandoned.append(True)


def exit_now(code: int) -> None:
    """End the process at once with `code` if a stop left native work running (its outputs
    are already removed); a process whose threads are all Python's returns."""
    if _abandoned:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)


def clear_stop_signal() -> None:
    """Forget a stop of an earlier command in this process."""
    _stopped.clear()


def stop_signal() -> int | None:
    """SIGINT or SIGTERM if one stopped an output under way. The exception it raised may have
    been swallowed by a library's callback (Gmsh's size field, PETSc's residual), which then
    fails in its own words: the caller asks here what really happened."""
    return _stopped[-1] if _stopped else None


@contextlib.contextmanager
def _stop_cleanly():
    """Turn SIGINT and SIGTERM into exceptions for the block (main thread only), so that the
    work under way unwinds and its temporary directories are removed. Installed when the
    command holds its output (reserved, or atomic_directory alone), after the libraries it
    loaded set handlers of their own; within a block that has them already, nothing changes
    (a stop noted earlier in the command is kept)."""
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is _stop:
        yield
        return
    _stopped.clear()
    previous = {s: signal.signal(s, _stop) for s in STOPS}
    hook = sys.unraisablehook

    def quiet(unraisable):   # a stop swallowed by a callback is reported once, by the CLI
        if not isinstance(unraisable.exc_value, (KeyboardInterrupt, Terminated)):
            hook(unraisable)

    sys.unraisablehook = quiet
    try:
        yield
    finally:
        sys.unraisablehook = hook
        for s, handler in previous.items():
            signal.signal(s, handler)


@contextlib.contextmanager
def declared_inputs(paths):
    """Within the block, every output check (check_output, atomic_directory) also refuses an
    `--out` holding any of `paths` (the files the command reads)."""
    token = _DECLARED.set(tuple(str(p) for p in paths if p is not None))
    try:
        yield
    finally:
        _DECLARED.reset(token)


@contextlib.contextmanager
def declared_command(name: str):
    """Within the block, outputs are the command `name`'s: its marker says so, and an output
    of another command is not replaced (a `pinbore export` into a `pinbore modes` folder
    had replaced its body.npz)."""
    token = _COMMAND.set(name)
    try:
        yield
    finally:
        _COMMAND.reset(token)


def _writer(out: Path) -> str | None:
    """The command that wrote the output `out`, from its marker (None: not said: an older
    pinbore's marker, or no marker)."""
    try:
        lines = (out / MARKER).read_text().splitlines()
    except (OSError, UnicodeDecodeError):
        return None
    return next((line.removeprefix("command: ") for line in lines if line.startswith("command: ")), None)


def _inside(path: Path, folder: Path) -> bool:
    """Whether `path` is `folder` or lies below it (both resolved)."""
    return path == folder or folder in path.parents


def check_output(out, inputs=()) -> Path:
    """`out` as a Path if a run may write it (see the module's rules), else an InputError
    naming the rule. `inputs`: files or folders the run reads, which `out` must not hold."""
    text = str(out)
    if text.strip() in ("", "."):
        raise InputError(f"--out {text!r}: must name a directory of its own (not '' or '.')")
    out = Path(out)
    where = out.resolve()
    if _inside(Path.cwd().resolve(), where):
        raise InputError(f"--out {text}: is the working directory or a folder above it; "
                         "name a directory of its own")
    for item in (*inputs, *_DECLARED.get()):
        if item is not None and _inside(Path(item).resolve(), where):
            raise InputError(f"--out {text}: holds the input {item}; pinbore would replace it "
                             "(choose another output directory)")
    if out.exists() or out.is_symlink():
        if not out.is_dir():
            raise InputError(f"--out {text}: is a file, not a directory (pinbore replaces "
                             "only directories it wrote)")
        if not (out / MARKER).is_file() and any(out.iterdir()):
            raise InputError(f"--out {text}: a directory that pinbore did not write (no "
                             f"{MARKER} in it; older pinbore versions wrote none) and that is "
                             "not empty; choose another, or empty or remove it")
        writer, command = _writer(out), _COMMAND.get()
        if writer is not None and command is not None and writer != command:
            raise InputError(f"--out {text}: holds the output of pinbore {writer}, which pinbore "
                             f"{command} does not replace; choose another output directory")
    parent = where.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise InputError(f"--out {text}: {parent} is a file, not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"--out {text}: cannot write in {parent} (permission denied)")
    return out


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _temporary_prefix(out: Path, pid: int) -> str:
    """Name prefix of the temporary directories of `out` written by process `pid`."""
    return f".{out.name}.pinbore-{pid}-"


def _sweep_stale(out: Path) -> None:
    """Remove temporary directories of `out` left by processes that no longer run."""
    own = re.compile(re.escape(f".{out.name}.pinbore-") + r"(\d+)-[^.]*\.tmp")
    for stale in out.parent.iterdir():
        match = own.fullmatch(stale.name)
        if match and not _alive(int(match.group(1))):
            shutil.rmtree(stale, ignore_errors=True)


@contextlib.contextmanager
def _lock(out: Path):
    """Hold an exclusive lock on `out` (a lock file beside it) or refuse at once."""
    path = out.parent / f".{out.name}.pinbore-lock"
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise InputError(f"--out {out}: another pinbore run is writing it now") from None
        try:   # the file we locked may have been removed by its last holder: lock the new one
            if os.fstat(fd).st_ino == os.stat(path).st_ino:
                break
        except FileNotFoundError:
            pass
        os.close(fd)
    try:
        yield
    finally:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        os.close(fd)


def _remove_empty(folders) -> None:
    """Remove the folders (innermost first) that are still empty."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


def _on_rank0(comm, out: Path, work):
    """work() on rank 0 (the file system's owner), its value broadcast to every rank; an
    InputError, or an OSError of the folder (a full disk, a read-only folder), raised on every
    rank as one InputError line."""
    error = value = None
    if comm.rank == 0:
        try:
            value = work()
        except InputError as err:
            error = str(err)
        except OSError as err:
            error = f"--out {out}: cannot write there ({err.strerror or err})"
    error, value = comm.bcast((error, value), root=0) if comm.size > 1 else (error, value)
    if error:
        raise InputError(error)
    return value


@contextlib.contextmanager
def reserved(out: str | Path, comm=MPI.COMM_WORLD):
    """Hold the output `out` for a whole command, from before its work: checked
    (check_output), locked (a second run writing it is refused at once, not after computing),
    and SIGINT and SIGTERM turned into exceptions (KeyboardInterrupt, Terminated) for the
    block, so that a stop anywhere in the work unwinds it cleanly. atomic_directory(out)
    within the block writes under this lock. The folders made to hold the lock are removed
    again if the block leaves them empty (bad input writes nothing)."""
    out = Path(out)
    with contextlib.ExitStack() as held:
        held.enter_context(_stop_cleanly())

        def hold():
            with signals_held():   # what it makes is registered for removal before a stop lands
                check_output(out)
                missing, parent = [], out.absolute().parent
                while not parent.exists():
                    missing.append(parent)
                    parent = parent.parent
                out.absolute().parent.mkdir(parents=True, exist_ok=True)
                held.callback(_remove_empty, missing)
                held.enter_context(_lock(out))

        _on_rank0(comm, out, hold)
        token = _RESERVED.set(out.resolve())
        held.callback(_RESERVED.reset, token)
        yield out


@contextlib.contextmanager
def atomic_directory(out: str | Path, comm=MPI.COMM_WORLD, inputs=()):
    """Yield a temporary directory that becomes `out` when the block exits cleanly.

    `out` is checked (check_output, with the run's `inputs`) and locked first (unless the
    command holds it already: `reserved`). An exception,
    Ctrl-C or SIGTERM (raised as KeyboardInterrupt, Terminated) removes the temporary
    directory. A run that stops early but keeps what it computed (non-convergence) writes its
    files, marks them, and leaves the block normally.
    """
    out = Path(out)
    with contextlib.ExitStack() as held:
        held.enter_context(_stop_cleanly())

        def start():
            # with stops held, so that what it makes (the lock, the temporary folder) has its
            # removal registered before a stop lands; on success the folder is renamed
            with signals_held():
                check_output(out, inputs)
                out.parent.mkdir(parents=True, exist_ok=True)
                if _RESERVED.get() != out.resolve():
                    held.enter_context(_lock(out))
                check_output(out, inputs)   # again, now that no other run can change it
                _sweep_stale(out)
                tmp = tempfile.mkdtemp(prefix=_temporary_prefix(out, os.getpid()), suffix=".tmp",
                                       dir=out.parent)
                held.callback(shutil.rmtree, tmp, ignore_errors=True)
                return tmp

        tmp = Path(_on_rank0(comm, out, start))
        failed = None
        try:
            yield tmp
            _raise_if_stopped()
        except BaseException as err:
            failed = err
        # every rank gets here, so a rank that failed cannot leave the others waiting
        if not comm.allreduce(failed is None, op=MPI.LAND):
            if failed is not None:
                raise failed
            raise RuntimeError("another MPI rank failed; nothing written")
        if comm.rank == 0:
            _commit(tmp, out)
        comm.barrier()


@contextlib.contextmanager
def signals_held(drop: bool = False):
    """SIGINT and SIGTERM held off for the block, for a step that must happen whole (two
    renames, a worker process started): Python's handlers (which run in the main thread,
    whichever thread the signal reached) only note a signal meanwhile, and it is delivered to
    the handlers as the block ends (`drop`: dropped, and both ignored from then on: the
    caller restores the handlers). The main thread also blocks them, so that a process it
    starts begins with them blocked (a worker lets them through once it is ready,
    core.parallel). Elsewhere than in the main thread, nothing to hold."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    arrived = []

    def note(signum, frame):
        arrived.append(signum)

    # undone in reverse, each step whatever the one before raised: the mask lifted while the
    # noting handlers still stand (a signal pending meanwhile is noted), the handlers put
    # back, then what was noted delivered to them
    with contextlib.ExitStack() as undo:
        if not drop:
            undo.callback(lambda: [signal.raise_signal(s) for s in dict.fromkeys(arrived)])
        for s in STOPS:
            undo.callback(signal.signal, s, signal.SIG_IGN if drop else signal.getsignal(s))
            signal.signal(s, note)
        signal.pthread_sigmask(signal.SIG_BLOCK, STOPS)
        undo.callback(signal.pthread_sigmask, signal.SIG_UNBLOCK, STOPS)
        yield


def _commit(tmp: Path, out: Path) -> None:
    """Mark `tmp` as pinbore's and put it in place of `out`, with SIGINT and SIGTERM held off
    (a signal between the two renames would leave the old output under a temporary name)."""
    # a stop that comes meanwhile is dropped: the output is complete, and the run ends by
    # itself (the caller restores the handlers)
    with signals_held(drop=True):
        command = _COMMAND.get()
        (tmp / MARKER).write_text(MARKER_TEXT + (f"command: {command}\n" if command else ""))
        if out.exists():
            old = out.with_name(f"{_temporary_prefix(out, os.getpid())}old.tmp")
            out.rename(old)
            tmp.rename(out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            tmp.rename(out)
