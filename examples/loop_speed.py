#!/usr/bin/env python3
"""Your own TraCI loop against the CLI, side by side: wall time of one episode on a SUMO scenario.

Runs the same episode (scenario, planner, α, seed, steps) ``--rounds`` times each way, the ways
interleaved so that they share the machine's state: ``bkpbs episode --sumocfg`` (the CLI), and
``examples/traci_loop.py --sumocfg`` in this Python (the loop a user writes: ``Controller.step``
after each ``simulationStep``) through libsumo in-process and through traci. Prints each way's
median wall time (process start to exit, as a user waits for it), its ratio to the CLI's, and
whether its ``episode.csv`` and ``vehicles.csv`` equal the CLI's byte for byte.

    make wheel     # the documented install: release wheel + SUMO's libsumo wheel in .venv
    .venv/bin/python examples/loop_speed.py [--sumocfg FILE] [--steps N] [--rounds K] [--bin BKPBS]

``--bin`` defaults to ``bkpbs`` on PATH. Exit code 1 if a way fails or its files differ.
"""

from __future__ import annotations

import argparse
import filecmp
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from typing import Dict, List

#: The files of an episode that must agree, byte for byte.
COMPARED = ("episode.csv", "vehicles.csv")
LOOP = os.path.join(os.path.dirname(os.path.abspath(__file__)), "traci_loop.py")


def commands(args: argparse.Namespace, out: str) -> Dict[str, List[str]]:
    """The command of each way, writing its files into ``out/<way>``."""
    episode = ["--sumocfg", args.sumocfg, "--planner", args.planner, "--alpha", str(args.alpha),
               "--seed", str(args.seed), "--steps", str(args.steps)]
    loop = [sys.executable, LOOP, *episode]
    return {
        "cli": [args.bin, "episode", *episode, "--out", os.path.join(out, "cli")],
        "libsumo": [*loop, "--libsumo", "--out", os.path.join(out, "libsumo")],
        "traci": [*loop, "--out", os.path.join(out, "traci")],
    }


def timed(cmd: List[str]) -> float:
    """Wall seconds of ``cmd``; exits with its output if it fails."""
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"error: {' '.join(cmd[:3])} … failed: {(done.stderr or done.stdout).strip()}")
    return time.perf_counter() - t0


def same_files(out: str, way: str) -> bool:
    """Whether ``way``'s compared files equal the CLI's."""
    return all(filecmp.cmp(os.path.join(out, "cli", f), os.path.join(out, way, f), shallow=False)
               for f in COMPARED)


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sumo_home = os.environ.get("SUMO_HOME", "/usr/share/sumo")
    p.add_argument("--sumocfg", default=os.path.join(sumo_home, "tools/game/ramp.sumocfg"),
                   help="the scenario (default: SUMO's ramp game)")
    p.add_argument("--planner", default="bk-pbs")
    p.add_argument("--alpha", type=float, default=0.5)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--steps", type=int, default=400)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--bin", default=shutil.which("bkpbs") or "bkpbs", help="the bkpbs CLI")
    args = p.parse_args()
    walls: Dict[str, List[float]] = {}
    same = True
    with tempfile.TemporaryDirectory(prefix="bkpbs-loop-speed-") as tmp:
        for r in range(args.rounds):
            out = os.path.join(tmp, str(r))
            for way, cmd in commands(args, out).items():
                walls.setdefault(way, []).append(timed(cmd))
                same &= way == "cli" or same_files(out, way)
    cli = statistics.median(walls["cli"])
    print(f"{os.path.basename(args.sumocfg)}, {args.planner}, α={args.alpha}, seed={args.seed}, "
          f"{args.steps} steps, median of {args.rounds}:")
    for way, w in walls.items():
        m = statistics.median(w)
        print(f"  {way:<8} {m:7.2f} s  {m / cli:5.2f} × the CLI")
    print(f"  files ({', '.join(COMPARED)}): {'identical' if same else 'DIFFER'} across the ways")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
