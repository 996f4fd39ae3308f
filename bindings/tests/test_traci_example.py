"""examples/traci_loop.py end to end with real SUMO: through traci (a `sumo` subprocess), and
through libsumo when this interpreter has SUMO's Python libsumo."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import bkpbs
from conftest import REPO

EXAMPLE = REPO / "examples" / "traci_loop.py"


def run_example(*args):
    p = subprocess.run(
        [sys.executable, str(EXAMPLE), *args], capture_output=True, text=True, timeout=300
    )
    assert p.returncode == 0, p.stdout + p.stderr
    return p.stdout


@pytest.mark.parametrize("planner", ["idm-mobil", "bk-pbs"])
def test_traci_loop_short_episode(planner):
    out = run_example("--planner", planner, "--steps", "50", "--seed", "1")
    assert f"{planner} via traci" in out and "departed" in out
    departed = int(out.split(" departed")[0].rsplit(" ", 1)[1])
    assert departed > 0


def test_traci_loop_timing_against_the_rust_runner():
    out = run_example("--planner", "idm-mobil", "--steps", "50", "--timing")
    assert "per step (ms), traci loop" in out and "per step (ms), Rust runner" in out


def _libsumo_python():
    """An interpreter with SUMO's Python libsumo: this one, else Debian's own python3."""
    probe = "import sys; sys.path.append('/usr/share/sumo/tools'); import libsumo"
    for exe in (sys.executable, "/usr/bin/python3"):
        if os.path.isfile(exe) and subprocess.run([exe, "-c", probe], capture_output=True).returncode == 0:
            return exe
    return None


LIBSUMO_PYTHON = _libsumo_python()


@pytest.mark.skipif(LIBSUMO_PYTHON is None, reason="no Python interpreter with SUMO's libsumo")
def test_libsumo_loop_short_episode(tmp_path):
    # The wheel is abi3: another interpreter can import the installed package from a copy.
    shutil.copytree(Path(bkpbs.__file__).parent, tmp_path / "bkpbs")
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    p = subprocess.run(
        [LIBSUMO_PYTHON, str(EXAMPLE), "--planner", "idm-mobil", "--steps", "50", "--libsumo"],
        capture_output=True, text=True, timeout=300, env=env,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    assert "idm-mobil via libsumo" in p.stdout
