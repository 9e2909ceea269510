"""The benchmark tables: `bench-table` shows chosen columns of a committed `bench/*.csv`, read
when the docs are built, so a page's numbers are the table `make bench` last wrote.

    ```{bench-table} ../bench/fem2d.csv
    :columns: mesh; dofs; wall_time_s = wall time (s) | .1f; force_error_rel = force error | .1e
    :where: ranks = 1; method != penalty
    ```

`:columns:` lists the columns shown, separated by `;`: a column's name in the CSV's header,
optionally `= its heading` and `| a format` (Python's format specification, applied to a
cell that reads as a number; other cells are shown as written). `:where:` keeps the rows
whose cells equal (`=`) or differ from (`!=`) the values given, all of them. A column the
CSV does not have is an error, so a renamed column fails the build instead of vanishing.
The other options are those of `csv-table` (`:class:`, `:widths:`, ...).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

from docutils import nodes
from docutils.parsers.rst import directives
from docutils.parsers.rst.directives.tables import CSVTable
from docutils.utils import SystemMessagePropagation


def column_specs(text: str) -> list[tuple[str, str, str]]:
    """(name, heading, format) of each column named in `:columns:`."""
    specs = []
    for item in filter(None, (part.strip() for part in text.split(";"))):
        item, _, fmt = item.partition("|")
        name, _, heading = item.partition("=")
        name = name.strip()
        specs.append((name, heading.strip() or name, fmt.strip()))
    return specs


def conditions(text: str) -> list[tuple[str, bool, str]]:
    """(column, equal, value) of each condition of `:where:`."""
    found = []
    for item in filter(None, (part.strip() for part in text.split(";"))):
        equal = "!=" not in item
        name, _, value = item.partition("=" if equal else "!=")
        found.append((name.strip(), equal, value.strip()))
    return found


def formatted(cell: str, fmt: str) -> str:
    if not fmt or not cell.strip():
        return cell
    try:
        return format(float(cell), fmt)
    except ValueError:
        return cell


class BenchTable(CSVTable):
    required_arguments = 1
    optional_arguments = 0
    final_argument_whitespace = False
    has_content = False
    option_spec = {**CSVTable.option_spec, "columns": directives.unchanged_required,
                   "where": directives.unchanged}
    for _key in ("file", "url", "header", "header-rows"):
        option_spec.pop(_key, None)

    def run(self):
        self.options["header-rows"] = 1
        return super().run()

    def make_title(self):
        """The table's caption: the CSV's path from the repository's root (bench/x.csv)."""
        text = self.arguments[0].removeprefix("../")
        return nodes.title(text, "", nodes.literal(text, text)), []

    def get_csv_data(self):
        source = Path(self.state.document.current_source).parent / self.arguments[0]
        source = source.resolve()
        try:
            text = source.read_text(encoding="utf-8")
        except OSError as error:
            raise SystemMessagePropagation(self.reporter.severe(
                f"bench-table: cannot read {self.arguments[0]}: {error}", line=self.lineno))
        self.state.document.settings.record_dependencies.add(str(source))
        env = getattr(self.state.document.settings, "env", None)
        if env is not None:
            env.note_dependency(str(source))
        rows = list(csv.DictReader(io.StringIO(text)))
        header = list(rows[0]) if rows else next(csv.reader(io.StringIO(text)), [])
        specs = column_specs(self.options.get("columns", ""))
        where = conditions(self.options.get("where", ""))
        unknown = [name for name in [s[0] for s in specs] + [w[0] for w in where]
                   if name not in header]
        if unknown or not specs:
            raise SystemMessagePropagation(self.reporter.error(
                f"bench-table {self.arguments[0]}: no column {', '.join(unknown) or '(none named)'}"
                f" (its columns: {', '.join(header)})", line=self.lineno))
        kept = [row for row in rows
                if all((row[name] == value) == equal for name, equal, value in where)]
        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow([heading for _, heading, _ in specs])
        for row in kept:
            writer.writerow([formatted(row[name] or "", fmt) for name, _, fmt in specs])
        return out.getvalue().splitlines(), str(source)


def setup(app):
    app.add_directive("bench-table", BenchTable)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}
