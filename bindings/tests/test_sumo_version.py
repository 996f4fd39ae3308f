"""Which SUMO: the module runs the libsumo it was built against, and says which in every summary."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

import bkpbs


def test_every_summary_names_the_sumo_that_ran_it():
    summary = bkpbs.run_episode("idm-mobil", 0.5, 3000, 1, steps=20)
    assert summary["sumo_version"] == bkpbs.SUMO_VERSION
    assert bkpbs.SUMO_VERSION[0].isdigit() or bkpbs.SUMO_VERSION.startswith("v")


def test_a_run_against_another_libsumo_is_refused_in_one_line():
    """The module loaded with another SUMO's libsumocpp first (same soname) refuses to run."""
    other = os.environ.get("BKPBS_OTHER_SUMO_LIB", "")
    if not os.path.isfile(os.path.join(other, "libsumocpp.so")):
        pytest.fail(
            "no second SUMO to test against: BKPBS_OTHER_SUMO_LIB must name the directory of "
            f"another SUMO's libsumocpp.so (make test sets it), got {other!r}"
        )
    code = "import bkpbs; bkpbs.run_episode('idm-mobil', 0.5, 3000, 1, steps=5)"
    env = dict(os.environ, LD_LIBRARY_PATH=other)
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                          timeout=60)
    assert done.returncode != 0
    last = done.stderr.strip().splitlines()[-1]
    assert f"bkpbs was built against SUMO {bkpbs.SUMO_VERSION} but runs SUMO" in last, done.stderr
    assert "libsumocpp.so" in last
