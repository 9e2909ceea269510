"""`pinbore study`: the command's options, and the run: the plan validated, its points run
through the sweep engine (pinbore.core.sweep, cached), the outputs written in DIR."""

import json
import sys
import time
from pathlib import Path

import pydantic

from pinbore.core import sweep
from pinbore.core.errors import InputError
from pinbore.core.output import atomic_directory
from pinbore.core.sweep import named_files
from pinbore.study.figures import figures_of, tolerance_figure
from pinbore.study.plan import MAX_POINTS, Plan, planned_points
from pinbore.study.point import Point
from pinbore.study.schema import load
from pinbore.study.stats import statistics, tolerance
from pinbore.study.tables import PARQUET_ROWS, table, write_parquet, write_results


class Options(sweep.Runner):
    """The command line's options: the sweep engine's (core.sweep.Runner: --out, --scheduler,
    --workers, --cache) and the study's own."""

    ranks: int = pydantic.Field(default=1, ge=1)   # MPI ranks of an FE point
    force: bool = False   # a plan of more than MAX_POINTS points


def options(given: dict) -> Options:
    """The command line's options validated; a broken rule is one InputError line
    `--option: rule`."""
    try:
        return Options.model_validate({k: v for k, v in given.items() if v is not None})
    except pydantic.ValidationError as err:
        first = err.errors()[0]
        option = "--" + str(first["loc"][0]).replace("_", "-") if first["loc"] else "options"
        raise InputError(f"{option}: {first['msg'].removeprefix('Value error, ')}") from None


def command(args) -> int:
    """`pinbore study` on its parsed arguments (pinbore.stages)."""
    given = {"out": args.out, "workers": args.workers, "ranks": args.ranks,
             "scheduler": args.scheduler, "cache": args.cache, "force": args.force}
    return run(args.study, options(given))


def run(study_file, options: Options) -> int:
    """`pinbore study`: validate the study and every point, run them (cached), write the
    outputs. 0, or 1 when a point failed (the others are kept)."""
    path = Path(study_file)
    study = load(path)
    if (count := planned_points(study)) > MAX_POINTS and not options.force:
        raise InputError(f"{path}: the plan has {count:.3g} points, more than {MAX_POINTS:,} (each a "
                         "scene in memory before the first runs): fewer values or sampling.points, "
                         "or --force")
    plan = Plan(path, study)
    if options.ranks > 1 and not plan.stage.mpi:
        raise InputError(f"--ranks: MPI ranks run FE points (pinbore fem); {path}'s points are "
                         f"{plan.stage.name} runs, which run on one process")
    inputs = [path, plan.base_path, options.cache, *named_files(plan.scenes, plan.base_path.parent)]
    # --out is checked against every file a point reads, and locked, before the points run
    with atomic_directory(options.out, inputs=inputs) as tmp:
        start = time.perf_counter()
        task = Point(plan.stage.name, plan.base_path.parent, str(plan.base_path), plan.columns, options.ranks)
        records, fresh = sweep.run(task, plan.scenes, plan.keys, options, desc="study")
        wall = time.perf_counter() - start
        rows = table(plan, records, fresh)
        write_results(tmp / "results.csv", plan, rows)
        parquet = write_parquet(tmp / "results.parquet", plan, rows) if len(rows) >= PARQUET_ROWS else None
        for name, record in zip(plan.point_names, records):
            if record["result"].get("files"):
                (tmp / "points" / name).mkdir(parents=True)
                for file, text in record["result"]["files"].items():
                    (tmp / "points" / name / file).write_text(text)
        stats = statistics(plan, rows)
        (tmp / "statistics.json").write_text(json.dumps(stats, indent=2) + "\n")
        if study.sampling.method != "grid":   # a grid's points are chosen, not drawn
            figures_of(tmp, plan, rows, stats)
        failed = [r for r in rows if r["status"] != "complete"]
        summary = {"study_file": str(path), "base": str(plan.base_path), "stage": plan.stage.name,
                   "points": len(rows), "ran": sum(fresh), "from_cache": len(rows) - sum(fresh),
                   "complete": len(rows) - len(failed), "failed": len(failed),
                   "wall_time_s": wall, "point_seconds": sum(r["seconds"] for r in rows if r["ran"]),
                   "cache": str(options.cache)}
        if parquet is not None:
            summary["parquet"] = parquet
        if study.tolerance is not None:
            answer = tolerance(plan, rows)
            (tmp / "tolerance.json").write_text(json.dumps(answer, indent=2) + "\n")
            tolerance_figure(tmp / "tolerance.png", answer)
            summary["tolerance_half_width"] = answer["half_width"]
        (tmp / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    if failed:
        print(f"pinbore study: {path}: {len(failed)} of {len(rows)} points did not complete "
              f"(first: point {failed[0]['point']}: {failed[0]['status']}: {failed[0]['reason']}); "
              f"see {options.out}/results.csv", file=sys.stderr)
        return 1
    return 0
