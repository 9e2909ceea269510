"""The scene reference, generated from the scene models themselves.

Every scene kind is a pydantic model (`SCENES` below names them); its JSON Schema
(`model_json_schema()`) holds each key's type, default, bounds, allowed values, the key's
description and its table's docstring. This module turns that schema into the tables of the
docs' scene pages (the Sphinx directive `scene-reference`) and into the committed files
`docs/schemas/*.schema.json` that TOML editors read (`python docs/_ext/scene_reference.py`,
run by `make docs`). `tests/test_docs.py` holds the committed schemas equal to the models and
every shipped scene valid, so neither the pages nor the schemas can drift from the code.

Units: a key's unit is taken from its description when the description states one, from the
key's name (`_deg`, `_hz`, `_rpm`, `_s`), else from `UNITS` (docs/_ext/units.toml), the units
of the keys whose models do not state them. A number without a unit from any of the three is
a build warning (so a failed docs build), as is an entry of `UNITS` that names no key.
"""

from __future__ import annotations

import importlib
import json
import re
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
SCHEMAS = DOCS / "schemas"


@dataclass(frozen=True)
class Scene:
    name: str          # the page and the schema file: docs/schemas/<name>.schema.json
    models: tuple      # "module:Class" of each model; two or more: one of them by `kind`
    folder: str        # the shipped scenes, scenes/<folder>/*.toml
    command: str       # the command that reads it


SCENES = (
    Scene("fem", ("pinbore.fem.scene:FemScene",), "fem", "pinbore mesh, pinbore fem"),
    Scene("impact", ("pinbore.fem.impact.scene:ImpactScene",), "impact", "pinbore impact"),
    Scene("modes", ("pinbore.fem.modes.scene:ModesScene",), "modes", "pinbore modes"),
    Scene("mechanism", ("pinbore.reduced.mechanism.scene:PlanarScene",
                        "pinbore.reduced.mechanism.scene:SpatialScene"),
          "reduced", "pinbore reduced, pinbore dynamics"),
    Scene("wear", ("pinbore.reduced.wear.scene:WearScene",), "wear", "pinbore wear"),
)
UNITS_FILE = Path(__file__).with_name("units.toml")


def model(path: str):
    module, name = path.split(":")
    return getattr(importlib.import_module(module), name)


def models(scene: Scene) -> list:
    return [model(path) for path in scene.models]


def model_files(scene: Scene) -> list[str]:
    """The files of the modules a scene kind's models may be made of: each model's module and
    every module loaded below its package (a mechanism scene's clearance joints are in
    pinbore.reduced.mechanism.joints), what a change of its page follows."""
    found = set()
    for path in scene.models:
        name = path.split(":")[0]
        importlib.import_module(name)
        package = name.rpartition(".")[0]
        found |= {m.__file__ for key, m in list(sys.modules.items())
                  if (key == name or key.startswith(package + ".")) and getattr(m, "__file__", None)}
    return sorted(found)


def scene_model(scene: Scene, data: dict):
    """The model that reads `data`, a parsed scene of `scene`'s folder (by its `kind` key when
    the folder holds more than one kind, as `pinbore reduced` does)."""
    candidates = models(scene)
    if len(candidates) == 1:
        return candidates[0]
    for candidate in candidates:
        if candidate.model_fields["kind"].annotation.__args__[0] == data.get("kind"):
            return candidate
    raise ValueError(f"kind = {data.get('kind')!r} is none of {scene.models}")


def schema(scene: Scene) -> dict:
    """The JSON Schema of a scene file: the model's, or, for several kinds in one folder, one
    of them chosen by the `kind` key (a discriminated union)."""
    import typing

    import pydantic

    found = models(scene)
    if len(found) == 1:
        out = found[0].model_json_schema()
    else:
        union = typing.Annotated[typing.Union[tuple(found)], pydantic.Field(discriminator="kind")]
        out = pydantic.TypeAdapter(union).json_schema()
        out["title"] = f"{scene.name} scene"
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", **out}


def schema_text(scene: Scene) -> str:
    return json.dumps(schema(scene), indent=2, ensure_ascii=False) + "\n"


def write_schemas() -> list[Path]:
    """docs/schemas/<scene>.schema.json of every scene kind, rewritten where they changed."""
    SCHEMAS.mkdir(exist_ok=True)
    written = []
    for scene in SCENES:
        path = SCHEMAS / f"{scene.name}.schema.json"
        text = schema_text(scene)
        if not path.exists() or path.read_text(encoding="utf-8") != text:
            path.write_text(text, encoding="utf-8")
            written.append(path)
    return written


# ---- the keys, as rows: key, type, unit, default, rule

SUFFIX_UNITS = {"_deg": "deg", "_hz": "Hz", "_rpm": "rpm", "_s": "s"}
UNIT_WORDS = r"(?:kg|m|s|N|Pa|Hz|rad|deg|J|W|1)(?:\^-?\d)?"
UNIT = re.compile(rf"^(?:1/)?{UNIT_WORDS}(?:(?: ?/ ?| ){UNIT_WORDS})*$")


def units_table() -> dict[str, str]:
    return tomllib.loads(UNITS_FILE.read_text(encoding="utf-8"))


def described_unit(description: str | None) -> str | None:
    """The unit a key's description states: a parenthesis (`Young's modulus (Pa)`, `axial
    length (m): ...`) or its first clause (`m/s`, `kg m^2 about ...`, `Pa; default E`,
    `m (hertz_point)`)."""
    if not description:
        return None
    head = re.split(r"[,;:]| about | between | of ", description, maxsplit=1)[0]
    head = re.sub(r"\s*\([^()]*\)\s*$", "", head).strip()
    for candidate in [*re.findall(r"\(([^()]*)\)", description), head]:
        if UNIT.match(candidate.strip()):
            return candidate.strip()
    return None


@dataclass
class Row:
    key: str
    kind: str
    unit: str
    default: str
    rule: str


@dataclass
class Table:
    path: str          # dotted path of the TOML table ("" for the top level)
    array: bool        # an array of tables ([[path]])
    variant: str       # e.g. 'law = "dahl"' for one form of a table of several
    doc: str           # the table's docstring
    model: str         # the model's name ($defs key)
    rows: list


class Walker:
    """The tables of a scene schema, depth first, each table once per path."""

    def __init__(self, root: dict, units: dict[str, str]):
        self.defs = root.get("$defs", {})
        self.units = units
        self.used_units: set[str] = set()
        self.missing: list[str] = []
        self.tables: list[Table] = []

    def resolve(self, node: dict) -> tuple[str | None, dict]:
        if "$ref" in node:
            name = node["$ref"].rsplit("/", 1)[1]
            return name, self.defs[name]
        return None, node

    def alternatives(self, node: dict) -> list[dict]:
        """The non-null alternatives of anyOf / oneOf (recursively)."""
        if "anyOf" in node or "oneOf" in node:
            out = []
            for alt in node.get("anyOf", []) + node.get("oneOf", []):
                out += self.alternatives(alt)
            return out
        return [] if node.get("type") == "null" else [node]

    def objects(self, node: dict) -> list[tuple[str, dict]]:
        """The tables a value may be: (model name, schema) of each object alternative."""
        out = []
        for alt in self.alternatives(node):
            name, target = self.resolve(alt)
            if target.get("type") == "object" and "properties" in target:
                out.append((name, target))
        return out

    def walk(self, name: str, node: dict, path: str = "", array: bool = False, variant: str = ""):
        table = Table(path, array, variant, node.get("description", ""), name or "", [])
        self.tables.append(table)
        required = set(node.get("required", []))
        nested = []
        for key, prop in node.get("properties", {}).items():
            table.rows.append(self.row(name, key, prop, key in required))
            sub = f"{path}.{key}" if path else key
            items = prop.get("items") if prop.get("type") == "array" else None
            for alt in self.alternatives(prop):
                if alt.get("type") == "array":
                    items = alt.get("items")
            forms = self.objects(items) if items else self.objects(prop)
            for form_name, form in forms:
                label = ""
                if len(forms) > 1:
                    consts = [f'{k} = "{v["const"]}"' for k, v in form["properties"].items()
                              if "const" in v]
                    label = consts[0] if consts else form_name
                nested.append((form_name, form, sub, items is not None, label))
        for args in nested:
            self.walk(*args)

    def row(self, model: str, key: str, prop: dict, required: bool) -> Row:
        alts = self.alternatives(prop)
        optional = len(alts) < len(prop.get("anyOf", [prop])) or (
            "default" in prop and prop["default"] is None)
        kinds = [self.kind(alt) for alt in alts] or [self.kind(prop)]
        kind = " or ".join(dict.fromkeys(kinds))
        rules = [r for alt in alts or [prop] for r in self.bounds(alt)]
        description = prop.get("description", "")
        if "default" in prop:
            default = self.value(prop["default"])
        else:
            default = "required"
        unit = self.unit(model, key, description, kinds)
        rule = "; ".join(dict.fromkeys(rules))
        if description:
            rule = f"{rule}. {description}" if rule else description
        if optional and prop.get("default", "x") is None:
            default = "not set"
        return Row(key, kind, unit, default, rule)

    def unit(self, model: str, key: str, description: str, kinds: list[str]) -> str:
        entry = f"{model}.{key}"
        if entry in self.units:
            self.used_units.add(entry)
            return self.units[entry]
        stated = described_unit(description)
        if stated:
            return stated
        for suffix, unit in SUFFIX_UNITS.items():
            if key.endswith(suffix):
                return unit
        if any(k.endswith("float") for k in kinds):
            self.missing.append(entry)
            return "?"
        return ""

    def kind(self, node: dict) -> str:
        name, node = self.resolve(node)
        if name is not None and node.get("type") == "object":
            return "table"
        if "const" in node:
            return f'"{node["const"]}"'
        if "enum" in node:
            return "string"
        kind = node.get("type")
        if kind == "array":
            items = node.get("items", {})
            alts = self.alternatives(items)
            inner = " or ".join(dict.fromkeys(self.kind(a) for a in alts)) if alts else "value"
            size = ""
            if node.get("minItems") is not None and node.get("minItems") == node.get("maxItems"):
                size = f" ({node['minItems']})"
            if inner == "table":
                return "array of tables"
            return f"array{size} of {inner}"
        return {"number": "float", "integer": "integer", "boolean": "boolean",
                "string": "string"}.get(kind, kind or "value")

    def bounds(self, node: dict) -> list[str]:
        _, node = self.resolve(node)
        out = []
        for key, sign in (("exclusiveMinimum", ">"), ("minimum", ">="),
                          ("exclusiveMaximum", "<"), ("maximum", "<=")):
            if key in node:
                out.append(f"{sign} {self.value(node[key])}")
        if "enum" in node:
            out.append("one of " + ", ".join(self.value(v) for v in node["enum"]))
        if node.get("type") == "array":
            lo, hi = node.get("minItems"), node.get("maxItems")
            if lo is not None and lo != hi:
                out.append(f"at least {lo} item{'s' if lo > 1 else ''}")
            if hi is not None and lo != hi:
                out.append(f"at most {hi} items")
            for alt in self.alternatives(node.get("items", {})):
                out += [f"each {b}" for b in self.bounds(alt)]
        if "pattern" in node:
            out.append(f"matches {node['pattern']}")
        return out

    @staticmethod
    def value(v) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, dict):
            return "table (defaults below)" if v else "{}"
        return json.dumps(v)


def tables(scene: Scene) -> tuple[list[tuple[str, list[Table]]], list[str], set[str]]:
    """(model title, its tables) of each model of a scene kind; the numeric keys without a
    unit; the UNITS entries used."""
    units = units_table()
    out, missing, used = [], [], set()
    for found in models(scene):
        root = found.model_json_schema()
        walker = Walker(root, units)
        walker.walk(found.__name__, root)
        out.append((found.__name__, walker.tables))
        missing += walker.missing
        used |= walker.used_units
    return out, missing, used


def check_units() -> tuple[list[str], list[str]]:
    """(numeric keys without a unit, UNITS entries that name no key) over every scene kind."""
    missing, used = [], set()
    for scene in SCENES:
        _, m, u = tables(scene)
        missing += m
        used |= u
    stale = sorted(set(units_table()) - used)
    return sorted(set(missing)), stale


# ---- Sphinx: the directive `scene-reference NAME`

def setup(app):
    from docutils import nodes
    from docutils.parsers.rst import Directive, directives
    from sphinx.util import logging

    logger = logging.getLogger(__name__)

    def paragraph(text: str, literal: bool = False):
        if literal:
            return nodes.paragraph("", "", nodes.literal(text, text))
        return nodes.paragraph(text, text)

    def grid(header: list[str], rows: list[list], widths: list[int]):
        table = nodes.table(classes=["scene-keys"])
        group = nodes.tgroup(cols=len(header))
        table += group
        for width in widths:
            group += nodes.colspec(colwidth=width)
        head = nodes.thead()
        group += head
        line = nodes.row()
        for cell in header:
            line += nodes.entry("", paragraph(cell))
        head += line
        body = nodes.tbody()
        group += body
        for cells in rows:
            line = nodes.row()
            for k, cell in enumerate(cells):
                line += nodes.entry("", paragraph(cell, literal=(k == 0)))
            body += line
        return table

    class SceneReference(Directive):
        required_arguments = 1
        has_content = False
        option_spec = {"model": directives.unchanged}

        def run(self):
            env = self.state.document.settings.env
            scene = next((s for s in SCENES if s.name == self.arguments[0]), None)
            if scene is None:
                raise self.error(f"scene-reference: no scene kind {self.arguments[0]!r}")
            env.note_dependency(str(UNITS_FILE))
            for path in model_files(scene):
                env.note_dependency(path)
            found, missing, _ = tables(scene)
            for entry in missing:
                logger.warning(f"scene-reference: {entry} is a number without a unit: state it "
                               f"in the field's description or in {UNITS_FILE.name}",
                               location=(env.docname, self.lineno))
            out = []
            for title, model_tables in found:
                if len(found) > 1:
                    section = nodes.section(ids=[nodes.make_id(f"{scene.name}-{title}")],
                                            names=[nodes.fully_normalize_name(title)])
                    section += nodes.title(title, title)
                    out.append(section)
                    parent = section
                else:
                    parent = None
                for table in model_tables:
                    name = table.path or "(top level)"
                    label = f"[[{name}]]" if table.array else (f"[{name}]" if table.path else name)
                    if table.variant:
                        label += f" with {table.variant}"
                    sid = nodes.make_id(f"{scene.name}-{title}-{table.path or 'top'}-{table.variant}")
                    sub = nodes.section(ids=[sid], names=[])
                    sub += nodes.title(label, label)
                    if table.doc:
                        block = nodes.literal_block(table.doc, table.doc, classes=["docstring"])
                        block["language"] = "text"
                        sub += block
                    rows = [[r.key, r.kind, r.unit, r.default, r.rule] for r in table.rows]
                    sub += grid(["key", "type", "unit", "default", "rule"], rows, [16, 14, 8, 12, 50])
                    (parent.append(sub) if parent is not None else out.append(sub))
            return out

    app.add_directive("scene-reference", SceneReference)

    def stale_units(app_, env):
        _, stale = check_units()
        for entry in stale:
            logger.warning(f"scene-reference: {UNITS_FILE.name}: {entry} names no key of a scene "
                           "model (renamed or removed?)")

    app.connect("env-check-consistency", stale_units)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}


if __name__ == "__main__":
    changed = write_schemas()
    for path in changed:
        print(f"wrote {path.relative_to(ROOT)}")
    missing, stale = check_units()
    for entry in missing:
        print(f"{entry}: a number without a unit (description or {UNITS_FILE.name})", file=sys.stderr)
    for entry in stale:
        print(f"{UNITS_FILE.name}: {entry} names no key", file=sys.stderr)
    sys.exit(1 if missing or stale else 0)
