"""How a campaign scales with Ray nodes: the same grid through ``python -m bkpbs.campaign --ray``
on a cluster of 1 and then of 2 worker nodes of one CPU each (``local_cluster``: nodes that do
not see the campaign's files, so inputs and results travel through Ray), the node counts
interleaved over ``--rounds``. Prints per node count the median wall time of the driver, tasks
per second, the driver's own CPU time per task (its start included) and the speed-up over one
node; checks that every run's ``episodes.csv`` and ``vehicles.csv`` are the same bytes.

    make bench-cluster        # release wheel first; needs root and unshare
    .venv/bin/python bindings/tests/bench_cluster.py [--seeds N] [--steps N] [--rounds K]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Dict, List, Tuple

from local_cluster import ENV, Cluster

COMPARED = ("episodes.csv", "vehicles.csv")


def grid(args: argparse.Namespace) -> List[str]:
    return ["--planners", args.planners, "--alphas", "0.5", "--lambdas", "3000", "--seeds",
            str(args.seeds), "--steps", str(args.steps)]


def driver(cluster: Cluster, out: Path, args: argparse.Namespace) -> Tuple[float, float]:
    """One campaign through the cluster: its wall seconds and the driver's CPU seconds."""
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "bkpbs.campaign", "--ray", "--address",
                          cluster.address, "--out", str(out), "--no-report", *grid(args)],
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=ENV)
    output = p.stdout.read().decode()
    _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0 or " 0 failed" not in output:
        sys.exit(f"error: the campaign on {cluster.address} failed:\n{output}")
    return wall, usage.ru_utime + usage.ru_stime


def run(nodes: int, hidden: Path, out: Path, args: argparse.Namespace) -> Tuple[float, float]:
    cluster = Cluster(hidden)
    try:
        for _ in range(nodes):
            cluster.add_worker(1)
        cluster.wait_for_cpus(nodes)
        return driver(cluster, out, args)
    finally:
        cluster.stop()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--planners", default="idm-mobil,bk-pbs")
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--rounds", type=int, default=2)
    args = ap.parse_args()
    tasks = len(args.planners.split(",")) * args.seeds
    runs: Dict[int, List[Tuple[float, float]]] = {1: [], 2: []}
    first = None
    with tempfile.TemporaryDirectory(prefix="bkpbs-bench-cluster-") as tmp:
        hidden = Path(tmp)
        for r in range(args.rounds):
            for nodes in runs:
                out = hidden / f"n{nodes}-r{r}"
                runs[nodes].append(run(nodes, hidden, out, args))
                files = [(out / f).read_bytes() for f in COMPARED]
                first = first or files
                if files != first:
                    sys.exit(f"error: {out.name}'s files differ from the first run's")
    one = statistics.median(w for w, _ in runs[1])
    print(f"{tasks} episodes ({args.planners}, {args.steps} steps), median of {args.rounds}:")
    print("nodes  wall s  tasks/s  driver CPU ms/task  speed-up")
    for nodes, rs in runs.items():
        wall = statistics.median(w for w, _ in rs)
        cpu = statistics.median(c for _, c in rs)
        print(f"{nodes:>5}  {wall:6.1f}  {tasks / wall:7.2f}  {cpu * 1e3 / tasks:18.0f}  "
              f"{one / wall:7.2f}")
    print(f"files ({', '.join(COMPARED)}): identical across every run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
