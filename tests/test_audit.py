"""bench/audit.py's reading of a run (make stress): stderr's lines as a terminal leaves them,
and the outcome each exit, stderr and file check gives."""

import signal

import pytest
from conftest import ROOT
from conftest import bench_audit as audit

BAR = "continuation:   5%|▌         | 5/100 [00:00<00:09,  9.82point/s, locating a grazing]"
LINE = "pinbore dynamics: terminated; outputs under way removed"


@pytest.mark.parametrize("stderr, lines", [
    (f"{BAR}\r{BAR}\n{LINE}\n", [LINE]),                      # the line after the bar
    (f"{BAR}{LINE}\n\r{BAR}\n", []),                          # the bar redrawn over it
    (f"{LINE}\nmake: *** [Makefile:210: docs] Error 2\n", [LINE]),
    ("a\nb\n", ["a", "b"]),
])
def test_stderr_lines_are_what_a_terminal_shows(stderr, lines):
    assert audit().stderr_lines(stderr) == lines


def run(a, **values):
    return a.Run(argv=["x"], cwd=ROOT, **values)


@pytest.mark.parametrize("values, code, lines, extra, outcome", [
    ({}, 2, ["pinbore x: a: rule"], {}, "clean"),
    ({}, 2, ["warning", "pinbore x: a: rule"], {}, "other"),
    ({}, 3, ["pinbore x: internal error"], {}, "traceback"),
    ({}, 1, ["Traceback (most recent call last):"], {"stderr": "Traceback"}, "traceback"),
    ({}, -11, [], {}, "signal crash"),
    ({}, 139, [], {}, "signal crash"),
    ({}, 0, [], {"hung": True}, "hang"),
    ({}, 2, ["pinbore x: a: rule"], {"changed": ["laws.json"]}, "destroyed"),
    ({}, 2, ["pinbore x: a: rule"], {"left": [".out.pinbore-lock"]}, "other"),
    ({"check": lambda cwd, out: None}, 0, [], {}, "accepted"),
    ({"check": lambda cwd, out: "a frequency NaN"}, 0, [], {}, "garbage complete"),
    ({"signal": (signal.SIGTERM, "out", 1.0)}, 143, ["pinbore x: terminated"], {"sent": 1.0, "stop": 0.1}, "clean"),
    ({"signal": (signal.SIGTERM, "out", 1.0)}, -15, [], {"sent": 1.0, "stop": 0.1}, "clean"),
    ({"signal": (signal.SIGTERM, "out", 1.0)}, 143, ["pinbore x: terminated"], {"sent": 1.0, "stop": 9.0}, "other"),
    ({"signal": (signal.SIGTERM, "out", 1.0)}, 143, ["pinbore x: terminated"],
     {"sent": 1.0, "stop": 0.1, "running": True}, "other"),
    ({"signal": (signal.SIGINT, "out", 1.0)}, -15, [], {"sent": 1.0, "stop": 0.1}, "signal crash"),
])
def test_each_run_has_its_outcome(values, code, lines, extra, outcome):
    a = audit()
    given = {"stderr": "\n".join(lines), "hung": False, "sent": None, "stop": None, "changed": [],
             "appeared": [], "left": [], "running": False} | extra
    found, _ = a.classify(run(a, **values), code, lines, given["stderr"], "", given["hung"], given["sent"],
                          given["stop"], given["changed"], given["appeared"], given["left"], given["running"])
    assert found == outcome
