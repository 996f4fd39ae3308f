"""A SUMO scenario of the user's own from Python: ``run_episode(..., sumocfg=FILE)`` runs it in
the core's loop and returns the same ``episode.csv`` row, byte for byte in its files, as
``bkpbs episode --sumocfg`` on the command line."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

import bkpbs
from conftest import ramp_game




def test_a_scenario_of_your_own_gives_the_clis_row(tmp_path: Path, cli: Path) -> None:
    cfg = ramp_game(tmp_path)
    row = bkpbs.run_episode("bk-pbs", 0.5, seed=2, sumocfg=cfg, steps=250, out=tmp_path / "py")
    subprocess.run(
        [str(cli), "episode", "--sumocfg", str(cfg), "--planner", "bk-pbs", "--alpha", "0.5",
         "--seed", "2", "--steps", "250", "--out", str(tmp_path / "cli")],
        check=True, capture_output=True,
    )
    for f in ("episode.csv", "vehicles.csv", "regions.csv", "entries.csv", "collisions.csv"):
        assert (tmp_path / "py" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert row["scenario"] == "ramp.sumocfg"
    assert row["planner"] == "bk-pbs" and row["steps"] == 250
    assert row["sumo_version"] == bkpbs.SUMO_VERSION
    assert row["inserted"] == row["arrived"] + row["crashed"] + row["present"] > 20
    assert row["inserted_cav"] > 0 and row["controllable_crashed"] == 0


def test_the_scenario_interval_is_the_default_length(tmp_path: Path) -> None:
    cfg = tmp_path / "short.sumocfg"
    text = ramp_game(tmp_path).read_text().replace('<end value="400"/>', '<end value="30"/>')
    cfg.write_text(text)
    row = bkpbs.run_episode("idm-mobil", 0.3, seed=0, sumocfg=cfg)
    assert row["steps"] == 150


def test_a_demand_rate_with_a_scenario_of_your_own_is_refused(tmp_path: Path) -> None:
    with pytest.raises(bkpbs.BkpbsError, match="lam = 3000.*its own demand"):
        bkpbs.run_episode("bk-pbs", 0.5, 3000.0, 1, sumocfg=ramp_game(tmp_path))


def test_cavs_by_vehicle_type(tmp_path: Path) -> None:
    """``cav_types=[...]``: every vehicle of those types is a CAV and no other."""
    out = tmp_path / "trucks"
    row = bkpbs.run_episode("bk-pbs", 0.5, seed=1, sumocfg=ramp_game(tmp_path), steps=250,
                            cav_types=["truck"], out=out)
    assert row["cav_types"] == "truck"
    lines = (out / "vehicles.csv").read_text().splitlines()
    header = lines[0].split(",")
    kinds = {tuple(r.split(",")[header.index(c)] for c in ("type", "kind")) for r in lines[1:]}
    assert kinds == {("truck", "cav"), ("passenger", "hdv")}
    with pytest.raises(bkpbs.BkpbsError, match="'lorry'.*its types: .*truck"):
        bkpbs.run_episode("bk-pbs", 0.5, seed=1, sumocfg=ramp_game(tmp_path / "b"), steps=50,
                          cav_types=["lorry"])
