"""Run a campaign grid as independent tasks: on Ray, or in local processes.

    python -m bkpbs.campaign --ray [--address ADDR] --out DIR [--planners a,b] [--alphas 0.4,0.8]
        [--lambdas 2500,3000] [--seeds N] [--seed-base S] [--steps H] [--config FILE] [--shard k/n]
    python -m bkpbs.campaign --ray --out DIR --sumocfg A.sumocfg,B.sumocfg [--planners ...] ...

One task per episode. libsumo allows one simulation per process, so on Ray every task runs in a
worker process of its own (``max_calls=1``); locally (without ``--ray``) each of ``--workers``
processes runs its episodes one after another, as ``bkpbs campaign`` does. On Ray the
episodes' input files travel to the nodes and their results back through Ray's object store,
so the nodes need no file of the campaign's (see :mod:`bkpbs._ray_runner`); a task whose node
or worker is lost runs again (``--max-retries``, recorded in ``retries.csv``). The grid, the
resume state (finished cells are skipped), the per-episode files and the collected
``episodes.csv``/``vehicles.csv``/``timings.csv``/``failures.csv`` all come from the Rust core
(:class:`bkpbs.Campaign`), so the directory is the one ``bkpbs campaign`` writes and
``bkpbs report DIR`` reads. With ``--sumocfg`` the grid is planners × scenarios of your own ×
α × seeds, as ``bkpbs campaign --sumocfg``. On a Ray cluster every node needs SUMO and this
package, nothing else.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from typing import List, Optional, Sequence

from ._bkpbs import BkpbsError, Campaign, CampaignTask, report
from ._ray_runner import RETRIES_FILE, Failure, describe, run_on_ray

__all__ = ["Failure", "RETRIES_FILE", "main", "run_locally", "run_on_ray"]


def _run_task(task: CampaignTask) -> Optional[str]:
    """Runs one episode in this process: ``None`` when done, else the error message."""
    return task.run()


def _failed(task: CampaignTask, error: str) -> Failure:
    print(f"campaign: episode {describe(task)} failed: {error}", file=sys.stderr)
    return (task, error)


def run_locally(tasks: Sequence[CampaignTask], workers: int) -> List[Failure]:
    """Runs the tasks in ``workers`` local processes; returns the failures."""
    failures: List[Failure] = []
    if not tasks:
        return failures
    with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
        futures = {pool.submit(_run_task, t): t for t in tasks}
        for f in as_completed(futures):
            task = futures[f]
            try:
                error = f.result()
            except Exception as e:  # the worker process died
                error = f"worker process died during the episode ({type(e).__name__}: {e})"
                task.record_failure(error)
            if error is not None:
                failures.append(_failed(task, error))
    return failures


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m bkpbs.campaign",
        description="Run the planners × α × λ × seeds grid as independent tasks (Ray or local "
        "processes) into the layout of `bkpbs campaign`.",
    )
    p.add_argument("--out", required=True, help="results directory; re-running resumes it")
    p.add_argument("--ray", action="store_true", help="run the episodes as Ray tasks")
    p.add_argument("--address", help="Ray cluster address (default: start a local Ray)")
    p.add_argument("--num-cpus", type=int, help="CPUs of a local Ray (default: all)")
    p.add_argument(
        "--max-retries", type=int, default=2,
        help="Ray: runs again of a task whose worker or node is lost (default: 2)",
    )
    p.add_argument(
        "--workers", type=int, default=None, help="local processes without --ray (default: cores)"
    )
    p.add_argument("--config", help="campaign TOML file ([campaign] table and scenario settings)")
    p.add_argument("--planners", help="comma-separated planners [default: all]")
    p.add_argument("--alphas", help="comma-separated CAV penetrations α")
    p.add_argument("--lambdas", help="comma-separated arrival rates λ (veh/h)")
    p.add_argument(
        "--sumocfg", help="comma-separated scenarios of your own (.sumocfg): a grid over them"
    )
    p.add_argument("--seeds", type=int, help="seeds per cell")
    p.add_argument("--seed-base", type=int, help="first seed")
    p.add_argument("--steps", type=int, help="episode length in steps")
    p.add_argument("--shard", help="run only slice k/n of the grid")
    p.add_argument("--no-report", action="store_true", help="skip the tables and figures")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The command line; returns the exit code (1 on bad input or failed episodes)."""
    args = _parser().parse_args(argv)
    start = time.monotonic()
    try:
        campaign = Campaign(
            args.out,
            config=args.config,
            planners=args.planners,
            alphas=args.alphas,
            lambdas=args.lambdas,
            seeds=args.seeds,
            seed_base=args.seed_base,
            steps=args.steps,
            shard=args.shard,
            sumocfg=args.sumocfg,
        )
        tasks = campaign.prepare()
    except (BkpbsError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    workers = args.workers or os.cpu_count() or 1
    where = "Ray" if args.ray else f"{min(workers, max(len(tasks), 1))} local processes"
    print(
        f"campaign: {campaign.grid_size} episodes; shard {campaign.shard}; "
        f"to run: {len(tasks)} on {where}",
        flush=True,
    )
    try:
        if args.ray:
            failures = run_on_ray(
                tasks, args.address, args.num_cpus, out=args.out, max_retries=args.max_retries
            )
        else:
            failures = run_locally(tasks, workers)
    except KeyboardInterrupt:
        print(
            "campaign: stopped; the episodes stored so far stay, and the same command resumes",
            file=sys.stderr,
        )
        return 130
    summary = campaign.collect()
    print(
        f"campaign: ran {len(tasks)} episodes: {len(tasks) - len(failures)} done, "
        f"{len(failures)} failed, in {time.monotonic() - start:.1f} s; "
        f"{summary['collected']} episodes collected in {summary['episodes_csv']}",
        flush=True,
    )
    if summary["collected"] and not args.no_report:
        print(report([args.out]), end="")
    if summary["failed"]:
        print(
            f"error: {summary['failed']} episodes failed (see "
            f"{os.path.join(args.out, 'failures.csv')})",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
