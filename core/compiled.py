"""numba's on-disk cache, kept in step with the code a compiled module calls from other files.

numba's cache checks only the file a compiled function is defined in ("Notes on caching" in
numba's documentation): a module whose compiled functions call compiled functions or read
constants of other files would keep running stale code after an edit there alone. A module
calls `follow_compiled_in(globals(), files)` at its end: a digest of those files, kept
beside the cache, drops the module's cache index when they change, and its functions
compile afresh once.
"""

import hashlib
from pathlib import Path

import numba


def follow_compiled_in(namespace: dict, files) -> None:
    """Flush the cache of the compiled functions defined in the module whose globals are
    `namespace` if the files `files` (those its compiled code calls into) changed since the
    cache was last stamped."""
    module = namespace["__name__"]
    compiled = [f for f in namespace.values()
                if isinstance(f, numba.core.registry.CPUDispatcher) and f.py_func.__module__ == module]
    if not compiled:
        return
    digest = hashlib.sha256(b"".join(Path(f).read_bytes() for f in files)).hexdigest()
    stamp = Path(compiled[0].stats.cache_path) / f"{module.rpartition('.')[2]}.compiled_in.sha256"
    try:
        if stamp.exists() and stamp.read_text() == digest:
            return
        for function in compiled:
            function._cache.flush()
        stamp.write_text(digest)
    except OSError:
        pass   # no writable cache: numba compiles afresh anyway
