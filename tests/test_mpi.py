"""`mpiexec -n 2 pinbore fem` gives the same curve as one process."""

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import pinbore, scene_dict

MPIEXEC = Path(sys.executable).parent / "mpiexec"


def curve(path):
    rows = list(csv.DictReader(open(path)))
    return np.array([[float(r["force_per_length_N_per_m"]), float(r["half_angle_deg"])] for r in rows])


@pytest.mark.mpi
def test_two_ranks_match_one(write_scene, tmp_path):
    scene = write_scene(scene_dict(output={"fields": True, "picture": True}))
    serial = pinbore("fem", scene, "--out", tmp_path / "serial")
    assert serial.returncode == 0, serial.stderr
    parallel = subprocess.run([str(MPIEXEC), "-n", "2", sys.executable, "-m", "pinbore.cli", "fem",
                               str(scene), "--out", str(tmp_path / "mpi")],
                              capture_output=True, text=True, timeout=600)
    assert parallel.returncode == 0, parallel.stderr
    np.testing.assert_allclose(curve(tmp_path / "mpi" / "curve.csv"),
                               curve(tmp_path / "serial" / "curve.csv"), rtol=1e-8)
    assert (tmp_path / "mpi" / "contact.png").exists() and (tmp_path / "mpi" / "fields.xdmf").exists()
