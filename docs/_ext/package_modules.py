"""The API pages: `.. package-modules:: pinbore.fem` documents every module that the package
(and each of its rooms, the subfolders) holds when the docs are built, found on disk, so a
module added, moved or removed changes the pages without editing them.

The docstrings are plain text written for a terminal (formulas, aligned lists, source keys in
brackets), not reST: they are shown preformatted, as written. Signatures carry no type hints
(`autodoc_typehints = "none"` in conf.py), so that nitpicky mode checks the project's own
references only.
"""

from __future__ import annotations

import importlib
from pathlib import Path


def modules(package: str) -> list[str]:
    """The dotted names of the package's modules and of its rooms' (subfolders holding Python
    files, with or without __init__.py), sorted, the package's own __init__ first."""
    found = [package]
    top = importlib.import_module(package)
    for folder in map(Path, top.__path__):
        for path in sorted(folder.rglob("*.py")):
            parts = path.relative_to(folder).with_suffix("").parts
            if "__pycache__" in parts or any(p.startswith((".", "_")) and p != "__init__" for p in parts):
                continue
            name = ".".join([package, *parts])
            if parts[-1] == "__init__":
                name = name.removesuffix(".__init__")
            found.append(name)
    return sorted(dict.fromkeys(found), key=lambda n: (n.count("."), n))


def preformatted(app, what, name, obj, options, lines):
    """A plain-text docstring as one literal block."""
    if not any(line.strip() for line in lines):
        return
    body = [("    " + line) if line.strip() else "" for line in lines]
    lines[:] = ["::", "", *body, ""]


def setup(app):
    from docutils import nodes
    from docutils.parsers.rst import Directive
    from docutils.statemachine import StringList

    class PackageModules(Directive):
        required_arguments = 1
        has_content = False

        def run(self):
            package = self.arguments[0]
            env = self.state.document.settings.env
            if not hasattr(env, "package_modules_docs"):
                env.package_modules_docs = set()
            env.package_modules_docs.add(env.docname)
            out = []
            for name in modules(package):
                module = importlib.import_module(name)
                if getattr(module, "__file__", None):
                    env.note_dependency(module.__file__)
                section = nodes.section(ids=[nodes.make_id(f"module-section-{name}")],
                                        names=[nodes.fully_normalize_name(name)])
                title = f"{name} (the package)" if name == package else name
                section += nodes.title(title, title)
                text = StringList([f".. automodule:: {name}", ""], source=f"<{package}>")
                self.state.nested_parse(text, self.content_offset, section)
                out.append(section)
            return out

    app.add_directive("package-modules", PackageModules)

    def always_outdated(app_, env, added, changed, removed):
        """The API pages are read again at every build: a module added to a floor is no file
        they depend on yet."""
        return sorted(getattr(env, "package_modules_docs", set()) - set(removed))

    def forget(app_, env, docname):
        getattr(env, "package_modules_docs", set()).discard(docname)

    def merge(app_, env, docnames, other):
        env.package_modules_docs = getattr(env, "package_modules_docs", set()) | (
            getattr(other, "package_modules_docs", set()) & set(docnames))

    app.connect("env-get-outdated", always_outdated)
    app.connect("env-purge-doc", forget)
    app.connect("env-merge-info", merge)
    app.connect("autodoc-process-docstring", preformatted)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}
