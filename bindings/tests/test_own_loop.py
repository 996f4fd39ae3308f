"""``Controller(sumocfg=...)`` in a TraCI loop of the user's own, on SUMO's shipped ``A10KW``
interchange: the loop starts SUMO, steps it and closes it; the controller plans every merge
region and commands the CAVs through the loop's ``traci``, and its ``finish`` gives the rows and
files ``bkpbs episode --sumocfg`` gives for the same scenario and seed, byte for byte."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import bkpbs

SUMO_HOME = Path(os.environ.get("SUMO_HOME", "/usr/share/sumo"))


@pytest.fixture(scope="module")
def traci():
    """SUMO's own ``traci`` (its tools directory), which drives the ``sumo`` binary of the
    SUMO bkpbs was built against."""
    tools = str(SUMO_HOME / "tools")
    if tools not in sys.path:
        sys.path.append(tools)
    import traci as module

    return module


def _interchange(dest: Path) -> Path:
    """SUMO's ``A10KW`` game, copied as a user would, at the planners' step of 0.2 s."""
    game = SUMO_HOME / "tools" / "game"
    shutil.copytree(game / "A10KW", dest / "A10KW")
    shutil.copy(game / "input_additional.add.xml", dest / "input_additional.add.xml")
    text = (game / "A10KW.sumocfg").read_text()
    cfg = dest / "A10KW.sumocfg"
    cfg.write_text(text.replace('<step-length value="0.5"/>', '<step-length value="0.2"/>'))
    return cfg


def _own_loop(traci, ctl: bkpbs.Controller) -> None:
    """The user's loop: start SUMO with the controller's command, step, close."""
    traci.start(ctl.sumo_command)
    try:
        ctl.start(traci)
        for _ in range(ctl.steps):
            traci.simulationStep()
            ctl.step(traci)
    finally:
        traci.close()


def test_your_own_traci_loop_gets_the_clis_episode(tmp_path: Path, cli: Path, traci) -> None:
    cfg = _interchange(tmp_path)
    ctl = bkpbs.Controller("bk-pbs", sumocfg=cfg, alpha=0.5, seed=3, steps=400)
    assert ctl.steps == 400 and ctl.commands_cavs
    assert ctl.sumo_command[:3] == ["sumo", "-c", str(cfg)]
    _own_loop(traci, ctl)
    row = ctl.finish(out=tmp_path / "loop")
    subprocess.run(
        [str(cli), "episode", "--sumocfg", str(cfg), "--planner", "bk-pbs", "--alpha", "0.5",
         "--seed", "3", "--steps", "400", "--out", str(tmp_path / "cli")],
        check=True, capture_output=True,
    )
    for f in ("episode.csv", "vehicles.csv", "regions.csv", "entries.csv", "collisions.csv"):
        assert (tmp_path / "loop" / f).read_bytes() == (tmp_path / "cli" / f).read_bytes(), f
    assert row["scenario"] == "A10KW.sumocfg" and row["steps"] == 400
    assert row["inserted"] == row["arrived"] + row["crashed"] + row["present"] > 100
    assert row["inserted_cav"] > 0 and row["controllable_crashed"] == 0
    regions = (tmp_path / "loop" / "regions.csv").read_text().splitlines()
    assert len(regions) == 3, regions  # both carriageways' merges


def test_the_loop_is_kept_in_order(tmp_path: Path, traci) -> None:
    cfg = _interchange(tmp_path)
    ctl = bkpbs.Controller("idm-mobil", sumocfg=cfg, alpha=0.3, seed=0, steps=5)
    with pytest.raises(bkpbs.BkpbsError, match="stepped with step"):
        ctl.plan([])
    with pytest.raises(bkpbs.BkpbsError, match="start the episode"):
        ctl.step(traci)
    traci.start(ctl.sumo_command)
    try:
        ctl.start(traci)
        for _ in range(5):
            traci.simulationStep()
            ctl.step(traci)
        with pytest.raises(bkpbs.BkpbsError, match="5 steps, all booked"):
            ctl.step(traci)
        with pytest.raises(bkpbs.BkpbsError, match="close SUMO"):
            ctl.finish()
    finally:
        traci.close()
    assert ctl.finish()["steps"] == 5
    with pytest.raises(bkpbs.BkpbsError, match="finished"):
        ctl.finish()
    with pytest.raises(bkpbs.BkpbsError, match="net_file was given with sumocfg"):
        bkpbs.Controller("bk-pbs", sumocfg=cfg, net_file=cfg)
    with pytest.raises(bkpbs.BkpbsError, match="sumocfg"):
        bkpbs.Controller("bk-pbs").start(traci)
