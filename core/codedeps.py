"""The code a stage runs, read from the source: the import closure of its entry, found
with `ast` (nothing is imported). make's dependencies (build/deps.mk) and the caches of the
study and of the dynamics sweeps come from here, so that an edit of any module a stage
imports reruns that stage and a cached result never stands for other code.

An entry is a module (`pinbore.fem.run`) or a function or class in one
(`pinbore.cli:main`, `pinbore.stages:fem_point`). Its closure holds:

- the module of the entry, its statements outside functions (what importing it runs) and, for a
  function or class entry, that definition whole;
- every project module these import, each whole: imports inside functions count (stages
  import lazily), and so does, in a module that loads modules by name
  (`importlib.import_module`: a registry, as `reduced.mechanism.kinds` and `pinbore.report`
  are), a module named by a string outside its functions (its table);
- the packages above each module, their statements outside functions (importing a module
  runs its packages' `__init__`; their lazy attributes, `pinbore.run`, are not followed);
- the compiled modules reached (COMPILED: no source; make rebuilds them with .venv).

A dispatcher, a module whose functions and table reach every stage (`pinbore.cli`, the stage
registry `pinbore.stages`), counts for what importing it runs, and is an entry by its
function: the closure of the module whole would be every stage.

The code a stage runs is named in the registry (pinbore/stages.py, read here with `ast`):
each `Stage(...)` names its scene model, runner, point function, report sections ... as
"module:name" strings. The code of a stage's fields is those modules whole (a dispatcher's
function alone), with the registry's own Stage class and resolve; a stage that runs every
stage's code of some fields (`uses`: the study runs every model, runner and point; the report
every section) has those too.

Run as a script (stdlib only, no install needed: `python3 -I core/codedeps.py`), it prints
the make dependency file of the repository it lies in (`make` writes it to build/deps.mk): per
command of `pinbore` (a stage of the registry), CODE_<command> the source files of the closure
of the command line's entry and of the stage's model and runner; and LAWS_SCENES, the
mechanism scenes (scenes/reduced/) whose TOML names a `laws_file`, which wait for the
calibration.
"""

import ast
import hashlib
import sys
import tomllib
from pathlib import Path

COMPILED = ("pinbore.core.cpp",)   # the compiled core (cpp/): part of the floor it lies in
CLI = "pinbore.cli"                # the `pinbore` command: main dispatches to the registry
REGISTRY = "pinbore.stages"        # the stage registry: STAGES, each stage's code in strings
DISPATCHERS = (CLI, REGISTRY)
REGISTRY_CODE = (f"{REGISTRY}:Stage", f"{REGISTRY}:resolve")   # how every stage is run
COMMAND_CODE = ("model", "run")    # the fields of a stage whose code its command runs
FIELD_CODE = {"point": ("model", "run", "point")}   # a study point runs its stage's model and runner
MECHANISM_SCENES = "scenes/reduced"
LAWS_KEY = "laws_file"             # a mechanism scene's key naming a calibration's laws.json


# ---- where the modules are

def repository_folders(root: Path) -> dict[str, list[Path]]:
    """Package -> its folders, by the package mapping of the repository's pyproject.toml
    (pinbore.core is core/, ..., pinbore is pinbore/): the source, with nothing installed."""
    mapping = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["scikit-build"]["wheel"]["packages"]
    return {package.replace("/", "."): [root / folder] for package, folder in mapping.items()}


def installed_folders() -> dict[str, list[Path]]:
    """Package -> its folders, as the running interpreter finds them (an editable install
    gives a floor two: its source, and the installed tree that holds a compiled module)."""
    import importlib.util   # noqa: PLC0415

    # the package is loaded (this module is pinbore.core.codedeps); not imported by name here,
    # which would put its lazy attributes, and so every stage, in every closure
    packages = ["pinbore", *(f"pinbore.{floor}" for floor in sys.modules["pinbore"].FLOORS)]
    return {package: list(dict.fromkeys(Path(p).resolve()
                                        for p in importlib.util.find_spec(package).submodule_search_locations))
            for package in packages}


def modules(folders: dict[str, list[Path]]) -> dict[str, Path | None]:
    """Dotted name -> source file of every module of the packages (subpackages included;
    the first folder that holds a name wins), and each compiled module, which has no
    source (None)."""
    found = {}
    for package, places in folders.items():
        for folder in places:
            for path in sorted(folder.rglob("*.py")):
                parts = path.relative_to(folder).with_suffix("").parts
                if "__pycache__" in parts or any(not p.isidentifier() for p in parts):
                    continue
                name = ".".join((package, *parts[:-1]) if parts[-1] == "__init__" else (package, *parts))
                found.setdefault(name, path)
    found.update(dict.fromkeys(COMPILED))
    return found


# ---- what a module imports

def project_module(name: str, known) -> str | None:
    """`name` if it is a module of the project, else its longest prefix that is (`from
    pinbore.fem.curve import Curve` imports pinbore.fem.curve); None outside the project."""
    parts = name.split(".")
    for end in range(len(parts), 0, -1):
        if ".".join(parts[:end]) in known:
            return ".".join(parts[:end])
    return None


def imported(nodes, name: str, is_package: bool, known, strings: bool = True) -> set[str]:
    """The project's modules that the statements `nodes` (of the module `name`) import:
    `import a.b`, `from a import b` (b when it is a module, else a), relative imports, and
    (with `strings`: a registry's table) a string constant that is a module's dotted name."""
    package = name if is_package else name.rpartition(".")[0]
    out = set()
    for node in nodes:
        if isinstance(node, ast.Import):
            out |= {project_module(alias.name, known) for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            out |= {project_module(f"{base}.{alias.name}", known) if f"{base}.{alias.name}" in known
                    else project_module(base, known) for alias in node.names}
        elif strings and isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in known:
            out.add(node.value)
    out.discard(None)
    out.discard(name)
    return out


def outside_functions(tree: ast.AST):
    """The nodes of a module that run when it is imported: all but the bodies of its
    functions (a class's body runs; its methods' do not)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                stack += child.decorator_list if not isinstance(child, ast.Lambda) else []
                continue
            stack.append(child)


def loads_by_name(tree: ast.Module) -> bool:
    """Whether a module loads modules by name (calls importlib.import_module): a registry,
    whose table names its modules in strings."""
    return any(isinstance(node, ast.Call) and (getattr(node.func, "attr", None) == "import_module"
                                               or getattr(node.func, "id", None) == "import_module")
               for node in ast.walk(tree))


def definition(tree: ast.Module, qualname: str) -> ast.AST:
    """The function or class `qualname` (dotted: Point.fem) of a module."""
    node = tree
    for part in qualname.split("."):
        node = next((n for n in ast.iter_child_nodes(node)
                     if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                     and n.name == part), None)
        if node is None:
            raise KeyError(qualname)
    return node


class Graph:
    """The import graph of the project's modules, parsed once."""

    def __init__(self, folders: dict[str, list[Path]]):
        self.files = modules(folders)
        self._trees, self._imports = {}, {}

    def tree(self, name: str) -> ast.Module | None:
        if name not in self._trees:
            path = self.files[name]
            self._trees[name] = None if path is None else ast.parse(path.read_text(), str(path))
        return self._trees[name]

    def imports(self, name: str, qualname: str | None = None, whole: bool = True) -> set[str]:
        """What module `name` imports: whole (every statement), or only what running it does
        (outside functions) and, with `qualname`, that definition whole."""
        key = (name, qualname, whole)
        if key not in self._imports:
            self._imports[key] = self._read_imports(name, qualname, whole)
        return self._imports[key]

    def _read_imports(self, name: str, qualname: str | None, whole: bool) -> set[str]:
        tree = self.tree(name)
        if tree is None:
            return set()
        package = self.files[name].stem == "__init__"
        strings = loads_by_name(tree) and name not in DISPATCHERS   # a dispatcher's strings: its stages
        found = imported(outside_functions(tree), name, package, self.files, strings=strings)
        if whole:
            found |= imported(ast.walk(tree), name, package, self.files, strings=False)
        if qualname is not None:
            found |= imported(ast.walk(definition(tree, qualname)), name, package, self.files,
                              strings=False)
        return found

    def closure(self, *entries: str) -> set[str]:
        """The modules the entries (`module` or `module:qualname`) run: see the module's
        docstring."""
        whole, run = self.closure_parts(*entries)
        return whole | run

    def closure_parts(self, *entries: str) -> tuple[set[str], set[str]]:
        """The closure in two: the modules read whole, and those of which only what importing
        them runs (an entry's module, the packages above a module)."""
        whole, run = set(), set()   # modules read whole; modules of which only the import runs
        todo = []
        for entry in entries:
            name, _, qualname = entry.partition(":")
            if name not in self.files:
                raise KeyError(f"{entry}: no module {name} in the project")
            if qualname:
                run.add(name)
                todo += [(m, True) for m in self.imports(name, qualname, whole=False)]
                todo += [(p, False) for p in parents(name)]
            else:
                todo.append((name, True))
        while todo:
            name, is_whole = todo.pop()
            is_whole = is_whole and name not in DISPATCHERS
            if name in whole or (not is_whole and name in run):
                continue
            (whole if is_whole else run).add(name)
            todo += [(m, True) for m in self.imports(name, whole=is_whole)]
            todo += [(p, False) for p in parents(name) if p in self.files]
        return whole, run - whole

    def sources(self, *entries: str) -> list[Path]:
        """The source files of the closure of the entries, sorted (compiled modules have none)."""
        return sorted(self.files[m] for m in self.closure(*entries) if self.files[m] is not None)


def parents(name: str) -> list[str]:
    """The packages above a module: pinbore.fem.modes.run -> pinbore, pinbore.fem, pinbore.fem.modes."""
    parts = name.split(".")
    return [".".join(parts[:end]) for end in range(1, len(parts))]


# ---- the uses: the caches' code hash, make's dependencies

_INSTALLED = None


def installed_graph() -> Graph:
    """The graph of the running interpreter's pinbore (parsed once per process)."""
    global _INSTALLED   # noqa: PLW0603
    if _INSTALLED is None:
        _INSTALLED = Graph(installed_folders())
    return _INSTALLED


def hashed(*entries: str) -> list[tuple[str, bytes]]:
    """What code_hash reads, by name: each module of the entries' closure and its source (a
    compiled module's binary); the module of a `module:qualname` entry by that definition's
    source alone (the rest of it is no code of the entry's, and its imports are followed),
    unless the closure reads it whole."""
    import importlib.util   # noqa: PLC0415

    graph = installed_graph()
    whole, _ = graph.closure_parts(*entries)
    own = {}
    for entry in entries:
        name, _, qualname = entry.partition(":")
        if qualname and name not in whole:
            text = graph.files[name].read_text()
            own[name] = own.get(name, b"") + ast.get_source_segment(
                text, definition(graph.tree(name), qualname)).encode()
    out = []
    for name in sorted(graph.closure(*entries)):
        path = graph.files[name] or Path(importlib.util.find_spec(name).origin)
        out.append((name, own[name] if name in own else path.read_bytes()))
    return out


def code_hash(*entries: str) -> str:
    """SHA-256 of the code the entries run (hashed: each module's name and source, each
    compiled module's binary), found without importing it: a cache keyed on it never serves
    a result of other code, and an edit of code they do not run keeps it."""
    digest = hashlib.sha256()
    for name, content in hashed(*entries):
        digest.update(f"{name}\0".encode())
        digest.update(content)
    return digest.hexdigest()


def registry(graph: Graph) -> dict[str, dict[str, list[str]]]:
    """Stage -> field -> the strings of that field, from each `Stage(...)` of the registry's
    source, in its order (nothing imported)."""
    stages = {}
    for node in ast.walk(graph.tree(REGISTRY)):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "Stage":
            fields = {k.arg: [c.value for c in ast.walk(k.value)
                              if isinstance(c, ast.Constant) and isinstance(c.value, str)]
                      for k in node.keywords}
            stages[fields["name"][0]] = fields
    return stages


def entry(graph: Graph, text: str) -> str | None:
    """The code entry a registry string names: "module:name" is the module whole (a
    dispatcher's: that function or class alone); None when it names no module of the project."""
    module, _, name = text.partition(":")
    if module not in graph.files:
        return None
    return text if module in DISPATCHERS and name else module


def stage_code(graph: Graph, stage: str, fields) -> list[str]:
    """The code entries of a stage's fields (a point's: FIELD_CODE), and of every stage that
    has a field the stage `uses` (the study: every stage's points; the report: every
    section), with the registry's REGISTRY_CODE."""
    stages = registry(graph)

    def code(of: dict, field: str) -> list[str]:
        return [text for f in FIELD_CODE.get(field, (field,)) for text in of.get(f, [])] if of.get(field) else []

    named = [text for field in fields for text in code(stages[stage], field)]
    named += [text for field in stages[stage].get("uses", []) for other in stages.values()
              for text in code(other, field)]
    return list(dict.fromkeys([*REGISTRY_CODE, *filter(None, (entry(graph, t) for t in named))]))


def commands(graph: Graph) -> dict[str, list[str]]:
    """The `pinbore` commands (the stages of the registry) and the code entries each runs: the
    command line's main, and its stage's model and runner (stage_code)."""
    return {stage: [f"{CLI}:main", *stage_code(graph, stage, COMMAND_CODE)] for stage in registry(graph)}


def laws_scenes(root: Path) -> list[str]:
    """The mechanism scenes (by file stem) whose TOML names a laws file: their runs read the
    calibration's laws.json."""
    return sorted(path.stem for path in (root / MECHANISM_SCENES).glob("*.toml")
                  if LAWS_KEY in tomllib.loads(path.read_text()))


def make_deps(root: Path) -> str:
    """The text of the make dependency file of the repository at `root` (paths relative to it)."""
    graph = Graph(repository_folders(root))
    lines = ["# build/deps.mk: written by core/codedeps.py from the source (do not edit): the",
             "# source files each `pinbore` command runs (the import closure of its stage's code",
             "# in the registry, pinbore/stages.py), and the mechanism scenes that read the",
             "# calibration's laws file"]
    for command, entries in commands(graph).items():
        files = [path.relative_to(root).as_posix() for path in graph.sources(*entries)]
        lines.append(f"CODE_{command} := {' '.join(files)}")
    lines.append(f"LAWS_SCENES := {' '.join(laws_scenes(root))}")
    # read again when any source file changes (a new file counts once a module imports it,
    # which is an edit); a file removed is no error (an empty rule, as gcc -MP writes)
    every = sorted(path.relative_to(root).as_posix() for path in graph.files.values() if path is not None)
    lines.append(f"build/deps.mk: {' '.join(every)}")
    lines += [f"{path}:" for path in every]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.stdout.write(make_deps(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent))
