"""The files between the stages, each defined by one module: curve.csv and pressure.csv
(pinbore.fem.curve), summary.json (pinbore.reduced.mechanism.summary). What is written reads back the
same, and a file a reader cannot take (another version's, or corrupt) is refused as one line
that names the file and what is wrong."""

import json

import numpy as np
import pytest
from conftest import pinbore

from pinbore.core.errors import InputError
from pinbore.fem import curve


def curve_rows(dim, stages=("push", "push", "push", "rotate")):
    """Rows of a curve.csv (fields of curve.Curve) with values in every column."""
    rows = []
    for i, stage in enumerate(stages, start=1):
        row = {f: 1e-3 * i + j for j, f in enumerate(curve.COLUMNS[dim])}
        rows.append(row | {"step": i, "stage": stage, "newton_iterations": 3 + i,
                           "uzawa_iterations": 1})
    return rows


@pytest.mark.parametrize("dim", [2, 3])
def test_curve_reads_back_what_was_written(tmp_path, dim):
    rows = curve_rows(dim)
    curve.write(tmp_path / "curve.csv", dim, rows)
    read = curve.read(tmp_path / "curve.csv")
    assert read.dim == dim and read.points == len(rows)
    for field, column in curve.COLUMNS[dim].items():
        values = [row[field] for row in rows]
        if column.kind is float:   # as written: to the column's format
            np.testing.assert_allclose(getattr(read, field), values, rtol=1e-3)
        else:
            assert list(getattr(read, field)) == values
    push = read.only("push")
    assert push.points == 3 and set(push.stage) == {"push"}


def test_the_variants_name_their_units():
    """2D: forces per unit length (N/m); 3D: of the whole pin (N). The rest is shared."""
    assert (curve.column(2, "force").name, curve.column(2, "force").unit) == \
        ("force_per_length_N_per_m", "N/m")
    assert (curve.column(3, "force").name, curve.column(3, "force").unit) == ("force_N", "N")
    shared = {f for f in curve.COLUMNS[2] if curve.column(2, f) == curve.column(3, f)}
    assert shared == set(curve.COLUMNS[2]) - {"force", "tangential_force", "friction_torque",
                                               "dissipated_work", "plastic_work"}


@pytest.mark.parametrize("dim", [2, 3])
def test_pressure_reads_back_what_was_written(tmp_path, dim):
    fields = curve.PRESSURE_COLUMNS[dim]
    rows = [{f: 0.5 * k for f in fields} | {"step": 1, "state": state}
            for k, state in enumerate(("open", "stick", "slip"))]
    curve.write_pressure(tmp_path / "pressure.csv", dim, rows)
    read = curve.read_pressure(tmp_path / "pressure.csv")
    assert read.dim == dim and list(read.state) == ["open", "stick", "slip"]
    np.testing.assert_allclose(read.pressure, [0.0, 0.5, 1.0])
    assert (read.z is None) == (dim == 2) and (read.shear_axial is None) == (dim == 2)


def _header_edit(edit):
    return lambda lines: [",".join(edit(lines[0].split(",")))] + lines[1:]


BAD_CURVES = [   # an edit of a written 2D curve.csv (its lines), what the one line must say
    (_header_edit(lambda h: h[:-1]), "gap_violation_m: required column is missing "
                                     "(written by another version of pinbore? run pinbore fem again)"),
    (lambda lines: [line + ",0" for line in lines], "0: unknown column"),
    (_header_edit(lambda h: [n.replace("force_per_length_N_per_m", "force_N") for n in h]),
     "force_N: units do not match; expected force_per_length_N_per_m (N/m)"),
    (_header_edit(lambda h: h[:-1] + ["step"]), "step: the column appears twice"),
    (lambda lines: lines[:2] + [lines[2].rsplit(",", 1)[0]] + lines[3:],
     "row 2: 16 cells, the header names 17"),
    (lambda lines: lines[:1] + [lines[1].replace("push", "squeeze")] + lines[2:],
     "stage: row 1: 'squeeze' is not one of push, rotate, slide"),
    (lambda lines: lines[:3] + [lines[3].replace(",1,", ",x,")] + lines[4:],
     "uzawa_iterations: row 3: 'x' is not an integer"),
    (lambda lines: lines[:1] + [",".join(lines[1].split(",")[:2] + ["inf"] + lines[1].split(",")[3:])]
     + lines[2:], "approach_m: row 1: inf is not finite"),
    (lambda lines: [], "empty file"),
]


@pytest.mark.parametrize("edit, message", BAD_CURVES)
def test_a_bad_curve_is_one_line_naming_file_and_fault(tmp_path, edit, message):
    path = tmp_path / "curve.csv"
    curve.write(path, 2, curve_rows(2))
    lines = edit(path.read_text().splitlines())
    path.write_text("\n".join(lines) + "\n" * bool(lines))
    with pytest.raises(InputError) as caught:
        curve.read(path)
    text = str(caught.value)
    assert text.startswith(f"{path}: ") and message in text and "\n" not in text


def test_a_summary_of_another_version_is_one_line(tmp_path):
    """The report reads summary.json through its model: a file without its keys is refused,
    in one line; the report is built without that section and exits 1 (incomplete)."""
    folder = tmp_path / "build" / "reduced" / "old_run"
    folder.mkdir(parents=True)
    (folder / "summary.json").write_text(json.dumps({"status": "complete"}))
    done = pinbore("report", "--build", tmp_path / "build", "--out", tmp_path / "report")
    assert done.returncode == 1, done.stderr
    line = done.stderr.strip()
    assert len(line.splitlines()) == 1 and str(folder / "summary.json") in line
    assert "model: required key is missing" in line and "run pinbore reduced again" in line
