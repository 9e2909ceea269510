"""numba's on-disk cache, kept in step with the code a compiled module calls from other files.

numba's cache checks only the file a compiled function is defined in ("Notes on caching" in
numba's documentation): a module whose compiled functions call compiled functions or read
constants of other files would keep running stale code after an edit there alone. A module
calls `follow_compiled_in(globals(), files)` at its end: a digest of those files, kept
beside the cache, drops the module's cache index when they change, and its functions
compile afresh once.

A module may also leave its functions uncompiled until first use (`compile_on_use`), so that
importing it, e.g. to validate a scene, does not load numba.
"""

import hashlib
from pathlib import Path


def follow_compiled_in(namespace: dict, files) -> None:
    """Flush the cache of the compiled functions defined in the module whose globals are
    `namespace` if the files `files` (those its compiled code calls into) changed since the
    cache was last stamped."""
    import numba   # noqa: PLC0415 (a module that calls this has loaded it)

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


def beside(file: str, *names: str) -> list[str]:
    """The files of the modules `names` in the folder of `file` (a module's own __file__):
    what its compiled code calls there, for follow_compiled_in."""
    folder = Path(file).parent
    return [str(folder / f"{name}.py") for name in names]


def compile_on_use(namespace: dict, options: dict[str, dict]):
    """The plain functions of a module (its globals `namespace`) named by `options` (name ->
    numba.njit's options), compiled on first use: they leave the module's globals, and the
    returned function, which the module takes as its __getattr__, compiles them all, in
    `options`' order (one may call another, a global by then), the first time one is asked
    for (`module.name` or `from module import name`) and returns it. Code of the module itself
    reaches them through that function."""
    plain = {name: namespace.pop(name) for name in options}

    def compiled(name: str):
        if name not in plain:
            raise AttributeError(f"module {namespace['__name__']!r} has no attribute {name!r}")
        if name not in namespace:
            import numba   # noqa: PLC0415

            for each, function in plain.items():
                namespace[each] = numba.njit(**options[each])(function)
        return namespace[name]

    return compiled
