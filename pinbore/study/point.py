"""One point of a study, run in a worker (`Point`: its scene through its stage's point
function in pinbore.stages), the statistic of a time-series column it collects, and the code
that may decide its result (`point_code`: the cache key's code)."""

import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from pinbore.core import scene as scenes
from pinbore.core.codedeps import installed_graph, stage_code
from pinbore.stages import STAGE, resolve

# the files of an FE or impact point's run kept in DIR/points/<name>/ (its data; not its plots)
KEPT_SUFFIXES = (".csv", ".json")


def point_code(stage: str) -> list[str]:
    """The code that may decide a point's result: its stage's scene model, runner and point
    function (pinbore.stages), read with what they import (core.codedeps: the import closure,
    lazy imports and the compiled core included); this module is hashed beside it whole (Point,
    the statistics of its series, the files it keeps; not the rest of pinbore.study: a new
    plot reruns nothing). An edit of the multibody engine so reruns no FE point."""
    return stage_code(installed_graph(), stage, ("point",))


def column_statistic(times: np.ndarray, values: np.ndarray, statistic: str,
                     window=None) -> float:
    """A statistic of a time series sampled at the run's accepted steps (times s, values in
    the column's unit), over the window [start, end] s (default: the whole run): max, min,
    max_abs, peak_to_peak and final of the step values; mean, rms and std weighted by time
    (trapezoidal rule over the steps, whose sizes vary), e.g. the rms of an attitude rate
    about its mean after a latch. NaN when the window holds fewer than two steps."""
    start, end = window if window is not None else (times[0], times[-1])
    inside = (times >= start) & (times <= end)
    t, x = times[inside], values[inside]
    if t.size < 2:
        return math.nan
    if statistic in ("max", "min", "max_abs", "peak_to_peak", "final"):
        return float({"max": np.max(x), "min": np.min(x), "max_abs": np.max(np.abs(x)),
                      "peak_to_peak": np.ptp(x), "final": x[-1]}[statistic])
    weights = np.zeros(t.size)
    weights[1:] += np.diff(t) / 2
    weights[:-1] += np.diff(t) / 2
    mean = float(weights @ x / (t[-1] - t[0]))
    if statistic == "mean":
        return mean
    if statistic == "rms":
        return math.sqrt(float(weights @ x**2 / (t[-1] - t[0])))
    return math.sqrt(max(float(weights @ (x - mean) ** 2 / (t[-1] - t[0])), 0.0))


class Point:
    """Runs one point's scene data in this process through its stage's point function
    (pinbore.stages: Stage.point) and returns {"status", "reason", "seconds", "result"}:
    status "complete", "suspect" (the run's verdict doubts it), "incomplete" (it stopped
    early) or "failed" (an error; reason says which)."""

    def __init__(self, stage: str, base: Path, source: str, columns=(), ranks: int = 1):
        # the base scene's folder, absolute where the study starts (a worker may run elsewhere)
        self.stage, self.base, self.source = stage, Path(base).absolute(), source
        self.columns = list(columns)   # (name, column, statistic, window) of a mechanism's series
        self.ranks = ranks             # of a point of an MPI stage: mpiexec -n ranks pinbore <stage>

    def __call__(self, data: dict) -> dict:
        start = time.perf_counter()
        try:
            status, reason, result = resolve(STAGE[self.stage].point)(data, self)
        except Exception as err:   # noqa: BLE001 (a point that fails is marked, the study goes on)
            status, reason, result = "failed", f"{type(err).__name__}: {err}", {}
        return {"status": status, "reason": reason, "seconds": time.perf_counter() - start,
                "result": result}

    def series(self, steps: dict) -> dict:
        """The statistics of the collected columns of a time series (name -> value)."""
        out = {}
        for name, column, statistic, window in self.columns:
            if column not in steps:
                raise KeyError(f"column {column!r}: not in the time series (columns: "
                               f"{', '.join(k for k in steps if k != 'time_s')})")
            out[name] = column_statistic(steps["time_s"], steps[column], statistic, window)
        return out

    def in_folder(self, data, read):
        """Run the stage's command on the point's scene, written as a scene file in a
        temporary folder (core.scene.scene_file: names of files made absolute), and read
        its result from the folder it wrote: read(out) -> dict."""
        with scenes.scene_file(data, self.base, f"{self.source} (a point's scene)") as path:
            out = path.parent / "out"
            code = self._run(path, out)
            if not out.is_dir():
                return "failed", f"the run wrote nothing (exit {code})", {}
            result = read(out)
            result["files"] = {f.name: f.read_text() for f in sorted(out.iterdir())
                               if f.suffix in KEPT_SUFFIXES}
        if code == 0:
            return "complete", "", result
        status = result.get("status") if result.get("status") in ("incomplete", "suspect") else "failed"
        reason = "; ".join(result.get("verdict") or []) or str(result.get("stop") or f"exit {code}")
        return status, reason, result

    def _run(self, path: Path, out: Path) -> int:
        """The stage's command on the scene file, in process or, with ranks, as `pinbore
        <stage>` on that many MPI processes (MPICH's mpiexec beside this Python, as the venv
        has it, else on PATH); its exit code."""
        if self.ranks == 1:
            return STAGE[self.stage].run_scene(path, out)
        mpiexec = Path(sys.executable).parent / "mpiexec"
        command = [str(mpiexec) if mpiexec.exists() else "mpiexec", "-n", str(self.ranks),
                   sys.executable, "-m", "pinbore.cli", self.stage, str(path), "--out", str(out)]
        return subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL).returncode
