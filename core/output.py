"""Outputs appear whole or not at all.

A run writes into a temporary sibling of its output directory and renames it into place
only when everything is written; a failed run leaves the old directory (if any) untouched.
Under MPI, rank 0 owns the file system: it creates the temporary directory, broadcasts its
name, and renames it when the ranks agree that the run succeeded.
"""

import contextlib
import shutil
import tempfile
from pathlib import Path

from mpi4py import MPI


@contextlib.contextmanager
def atomic_directory(out: str | Path, comm=MPI.COMM_WORLD):
    """Yield a temporary directory that becomes `out` when the block exits cleanly.

    An exception removes the temporary directory. A run that stops early but keeps what it
    computed (non-convergence) writes its files, marks them, and leaves the block normally.
    """
    out = Path(out)
    tmp = None
    if comm.rank == 0:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent)
    tmp = Path(comm.bcast(tmp, root=0))
    try:
        yield tmp
    except BaseException:
        if comm.rank == 0:
            shutil.rmtree(tmp, ignore_errors=True)
        raise
    comm.barrier()
    if comm.rank == 0:
        if out.exists():
            old = out.with_name(f".{out.name}.old")
            shutil.rmtree(old, ignore_errors=True)
            out.rename(old)
            tmp.rename(out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            tmp.rename(out)
    comm.barrier()


def write_text_atomic(path: str | Path, text: str) -> None:
    """Write a single file through a temporary name and a rename."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.rename(path)

