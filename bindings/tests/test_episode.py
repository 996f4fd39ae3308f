"""run_episode runs the core's episode loop: the same numbers and files as `bkpbs episode`."""

from __future__ import annotations

import csv
import subprocess

import pytest

import bkpbs
from conftest import csv_text


def read_row(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 1
    return rows[0]


@pytest.mark.parametrize("planner, seed, steps", [("idm-mobil", 3, 120), ("bk-pbs", 2, 40)])
def test_matches_the_cli(cli, tmp_path, planner, seed, steps):
    cli_out = tmp_path / "cli"
    subprocess.run(
        [str(cli), "episode", "--planner", planner, "--alpha", "0.6", "--lambda", "3000",
         "--seed", str(seed), "--steps", str(steps), "--out", str(cli_out)],
        check=True,
        capture_output=True,
    )
    py_out = tmp_path / "py"
    summary = bkpbs.run_episode(planner, 0.6, 3000, seed, steps=steps, out=py_out)
    row = read_row(cli_out / "episode.csv")
    assert list(summary) == list(row)
    for k, text in row.items():
        assert csv_text(summary[k], text) == text, k
    for name in ("episode.csv", "vehicles.csv", "collisions.csv"):
        assert (py_out / name).read_bytes() == (cli_out / name).read_bytes(), name
    assert summary["inserted"] > 0 and summary["planner"] == planner


def test_config_sources_agree(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[scenario]\nsteps = 30\n[idm]\ntime_headway = 1.2\n")
    a = bkpbs.run_episode("idm-mobil", 0.5, 2500, 4, config=f)
    b = bkpbs.run_episode("idm-mobil", 0.5, 2500, 4, steps=30, idm={"time_headway": 1.2})
    c = bkpbs.run_episode("idm-mobil", 0.5, 2500, 4, config={"scenario": {"steps": 30}, "idm": {"time_headway": 1.2}})
    assert a == b == c and a["steps"] == 30


def test_write_scenario_and_demand(tmp_path):
    files = bkpbs.write_scenario(tmp_path, 0.5, 3000, 0, steps=50)
    for k in ("net", "vtypes", "routes"):
        assert files[k].is_file()
    args = files["sumo_args"]
    assert args[0] == "sumo" and "--step-length" in args and "--lanechange.duration" in args
    assert args[args.index("--route-files") + 1] == str(files["routes"])
    n = bkpbs.write_demand(tmp_path / "d.rou.xml", 0.5, 3000, 0, steps=50)
    assert n == files["vehicles"] > 0
    assert (tmp_path / "d.rou.xml").read_text() == files["routes"].read_text()
