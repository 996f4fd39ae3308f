"""Shared fixtures: the repository, the `bkpbs` command-line binary, a hand-built scene."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path
from typing import Any, Dict, List

import pytest

REPO = Path(__file__).resolve().parents[2]

# Ray would try to report usage statistics over the network; the tests keep to this machine.
os.environ.setdefault("RAY_USAGE_STATS_ENABLED", "0")


def _target_dir() -> Path:
    t = os.environ.get("CARGO_TARGET_DIR")
    return Path(t) if t else REPO / "target"


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `bkpbs` binary: $BKPBS_BIN, else the one `cargo test` builds (built if missing)."""
    if os.environ.get("BKPBS_BIN"):
        return Path(os.environ["BKPBS_BIN"])
    exe = _target_dir() / "debug" / "bkpbs"
    if not exe.is_file():
        subprocess.run(
            ["cargo", "build", "--quiet", "--profile", "test", "--bin", "bkpbs"],
            cwd=REPO,
            check=True,
        )
    return exe


def vehicle(vid: str, kind: str, road: str, lane: int, pos: float, speed: float, **kw: Any) -> Dict[str, Any]:
    """A vehicle as a TraCI loop reads it, heading east along the road."""
    v = {
        "id": vid,
        "type": kind,
        "x": pos,
        "y": 0.0,
        "angle": 90.0,
        "speed": speed,
        "acceleration": 0.0,
        "lane_index": lane,
        "lane_position": pos,
        "road_id": road,
    }
    v.update(kw)
    return v


@pytest.fixture
def scene() -> List[Dict[str, Any]]:
    """CAVs and HDVs on every part of the merge: main road, ramp, acceleration lane, exit."""
    return [
        vehicle("main.0", "cav", "main_in", 0, 40.0, 30.0),
        vehicle("main.1", "hdv", "main_in", 0, 70.0, 26.0),
        vehicle("main.2", "cav", "main_in", 1, 20.0, 33.0),
        vehicle("main.3", "hdv", "acc", 2, 60.0, 31.0),
        vehicle("ramp.4", "cav", "ramp", 0, 120.0, 27.0, angle=76.0),
        vehicle("ramp.5", "hdv", "acc", 0, 30.0, 24.0),
        vehicle("ramp.6", "cav", "acc", 0, 90.0, 25.0, angle=88.0, lateral_offset=0.3),
        vehicle("main.7", "cav", "main_out", 1, 50.0, 34.0),
        vehicle("main.8", "hdv", "main_out", 0, 80.0, 28.0),
    ]


def csv_text(value: Any, like: str) -> str:
    """A summary value as `episode.csv` writes it: a float with the decimals the CSV text `like`
    shows (fixed per column; none for an integral α or λ), an int or text as is, None empty."""
    if value is None:
        return ""
    if isinstance(value, float):
        decimals = len(like.partition(".")[2])
        return f"{value:.{decimals}f}"
    return str(value)


def ramp_game(dest: Path) -> Path:
    """SUMO's shipped ``ramp`` game, copied as a user would (its files name each other)."""
    game = Path(os.environ.get("SUMO_HOME", "/usr/share/sumo")) / "tools" / "game"
    shutil.copytree(game / "ramp", dest / "ramp")
    for f in ("ramp.sumocfg", "input_additional.add.xml"):
        shutil.copy(game / f, dest / f)
    return dest / "ramp.sumocfg"
