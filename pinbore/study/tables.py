"""A study's results table: one row per point (its values, status, quantities), written as
results.csv and, from PARQUET_ROWS points, results.parquet."""

import math
import sys
from pathlib import Path

from pinbore.core.sweep import get
from pinbore.study.plan import Plan

# the number of points from which the results table is also written as Parquet (pyarrow)
PARQUET_ROWS = 1000


def table(plan: Plan, records: list[dict], fresh: list[bool]) -> list[dict]:
    """One row per point: its values, status, reason, quantities, whether it ran now."""
    rows = []
    for i, (values, record, ran, key) in enumerate(zip(plan.values, records, fresh, plan.keys)):
        row = {"point": i, "name": plan.point_names[i], **plan.cases[i],
               **dict(zip(plan.names, map(float, values))),
               "status": record["status"], "reason": record["reason"], "ran": ran,
               "seconds": record["seconds"], "key": key[:16]}
        for c in plan.study.collect:
            try:
                row[c.name] = float(get(record["result"], c.where))
            except (KeyError, TypeError, ValueError):
                row[c.name] = math.nan
                if row["status"] == "complete":
                    row["status"], row["reason"] = "failed", f"{c.where}: not in the result"
        rows.append(row)
    return rows


def results_header(plan: Plan) -> list[str]:
    return ["point", "name", *plan.study.cases, *plan.names, *(c.name for c in plan.study.collect),
            "status", "reason", "ran", "seconds", "key"]


def write_results(path: Path, plan: Plan, rows: list[dict]) -> None:
    from pinbore.reduced.dynamics.plots import write_table   # noqa: PLC0415

    header = results_header(plan)
    write_table(path, header, [[r[h] for h in header] for r in rows])


def write_parquet(path: Path, plan: Plan, rows: list[dict]) -> str:
    """The results table as Parquet (the columns of results.csv: the point an int64, ran a
    bool, the parameters, quantities and seconds float64, the rest strings), written with
    pyarrow (the optional extra `parquet`, in requirements.lock); without pyarrow, nothing is
    written and the answer says why."""
    try:
        import pyarrow as pa   # noqa: PLC0415
        import pyarrow.parquet as pq   # noqa: PLC0415
    except ImportError:
        print(f"pinbore study: {len(rows)} points: results.parquet not written (pyarrow is not "
              "installed: pip install 'pinbore[parquet]'); results.csv has the same table", file=sys.stderr)
        return "not written: pyarrow is not installed"
    numbers = {*plan.names, *(c.name for c in plan.study.collect), "seconds"}
    columns = {}
    for h in results_header(plan):
        values = [r[h] for r in rows]
        if h == "point":
            columns[h] = pa.array(values, type=pa.int64())
        elif h == "ran":
            columns[h] = pa.array(values, type=pa.bool_())
        elif h in numbers:
            columns[h] = pa.array(values, type=pa.float64())
        else:
            columns[h] = pa.array([str(v) for v in values], type=pa.string())
    pq.write_table(pa.table(columns), path)
    return path.name
