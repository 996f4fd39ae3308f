#!/usr/bin/env python3
"""The merge scenario driven from Python: SUMO through TraCI (or libsumo), CAVs by bkpbs.

This is how bkpbs plugs into an existing TraCI experiment: the loop below is yours (start SUMO,
step, read vehicles, command them); bkpbs only plans. Each step:

1. ``simulationStep``, then remove the vehicles of any collision (SUMO only reports them with
   the scenario's options, as in bkpbs's own runner);
2. ``bkpbs.read_vehicles``: every vehicle's type, angle, speed, acceleration, lane and road,
   read through one subscription per vehicle; only vehicles SUMO still knows, so not those
   just removed (their subscriptions end);
3. ``Controller.plan``: one maneuver per CAV, computed by the Rust core;
4. ``bkpbs.apply``: ``setSpeed`` / ``changeLane`` with SUMO's own checks off for CAVs.

The scenario files (network, vehicle types, the episode's demand as a route file) and SUMO's
options come from ``bkpbs.write_scenario``. Unlike ``bkpbs episode``, SUMO inserts the vehicles
from the route file itself and drives ramp HDVs with its own lane-change model.

    python examples/traci_loop.py --planner bk-pbs --steps 400 [--libsumo] [--timing]
        [--gui [--gui-delay MS]]

With ``--sumocfg FILE`` the loop runs a SUMO scenario of your own instead: SUMO loads your
configuration (net, routes, flows, vehicle types), a share α of its vehicles are CAVs, and
``Controller(sumocfg=FILE)`` books every step, plans every merge region and commands the CAVs
through the loop's module; at the end it prints the episode's row (``--out DIR``: its files,
those of ``bkpbs episode --sumocfg``).

    python examples/traci_loop.py --sumocfg my.sumocfg --alpha 0.3 --seed 1 [--steps N] [--out DIR]

``traci`` comes from ``$SUMO_HOME/tools`` (Debian: /usr/share/sumo/tools, package sumo-tools);
``--libsumo`` needs SUMO's Python libsumo: ``make wheel`` installs PyPI's ``libsumo`` wheel of
the SUMO bkpbs is built against into ``.venv`` (Debian's own is for its ``/usr/bin/python3`` only).
``--timing`` also runs the same episode in bkpbs's Rust runner and prints both per-step costs.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
import tempfile
import time
from typing import Any, Dict, List

import bkpbs


#: SUMO's directory on Debian (packages sumo, sumo-tools), used when $SUMO_HOME is unset.
DEBIAN_SUMO_HOME = "/usr/share/sumo"


def import_sumo(use_libsumo: bool) -> Any:
    """The TraCI module: ``traci`` (SUMO as a subprocess) or ``libsumo`` (in-process)."""
    if "SUMO_HOME" not in os.environ and os.path.isdir(DEBIAN_SUMO_HOME):
        os.environ["SUMO_HOME"] = DEBIAN_SUMO_HOME  # SUMO validates its XML input against it
    tools = [os.path.join(os.environ["SUMO_HOME"], "tools")] if "SUMO_HOME" in os.environ else []
    for t in tools:
        if os.path.isdir(t) and t not in sys.path:
            sys.path.append(t)
    try:
        if use_libsumo:
            import libsumo

            return libsumo
        import traci

        return traci
    except ImportError as e:
        what = "libsumo (`make wheel` installs it into .venv)" if use_libsumo else "traci"
        sys.exit(f"error: cannot import {what}: {e}; set SUMO_HOME to SUMO's directory")


def remove_collisions(sumo: Any, crashed: set) -> int:
    """Removes every vehicle in a collision of the last step (adding it to ``crashed``);
    returns how many collisions there were."""
    collisions = sumo.simulation.getCollisions()
    for c in collisions:
        for vid in (c.collider, c.victim):
            if vid not in crashed:
                sumo.vehicle.remove(vid)
                crashed.add(vid)
    return len(collisions)


def sumo_command(args: argparse.Namespace, files: Dict[str, Any]) -> List[str]:
    """SUMO's command line: the scenario's, in sumo-gui with ``--gui`` (started at once, closed
    at the end, paused ``--gui-delay`` ms per step, real time by default)."""
    cmd = list(files["sumo_args"])
    if args.gui:
        delay = args.gui_delay if args.gui_delay is not None else files["dt"] * 1000.0
        cmd[0] = "sumo-gui"
        cmd += ["--start", "true", "--quit-on-end", "true", "--delay", f"{delay:g}"]
    return cmd


def run(args: argparse.Namespace, sumo: Any, files: Dict[str, Any]) -> Dict[str, float]:
    """The TraCI loop; returns counts and seconds spent per phase."""
    controller = bkpbs.Controller(args.planner, net_file=args.net)
    dt = files["dt"]
    clock = time.perf_counter
    t = {"sumo": 0.0, "read": 0.0, "plan": 0.0, "apply": 0.0}
    departed = arrived = collisions = 0
    crashed: set = set()
    speed_sum = speed_samples = 0.0
    t_start = clock()
    sumo.start(sumo_command(args, files))
    loop_start = clock()
    try:
        for step in range(args.steps):
            t0 = clock()
            sumo.simulationStep()
            collisions += remove_collisions(sumo, crashed)
            departed += sumo.simulation.getDepartedNumber()
            # SUMO 1.15 also lists removed (crashed) vehicles as arrived.
            arrived += sum(v not in crashed for v in sumo.simulation.getArrivedIDList())
            t1 = clock()
            vehicles = bkpbs.read_vehicles(sumo)
            t2 = clock()
            if step + 1 == args.steps:  # the last step plans nothing, as in bkpbs's runner
                t["sumo"] += t1 - t0
                t["read"] += t2 - t1
                break
            maneuvers = controller.plan(vehicles, time=sumo.simulation.getTime())
            t3 = clock()
            bkpbs.apply(maneuvers, sumo, dt)
            t4 = clock()
            for key, a, b in (("sumo", t0, t1), ("read", t1, t2), ("plan", t2, t3), ("apply", t3, t4)):
                t[key] += b - a
            speed_sum += sum(v["speed"] for v in vehicles)
            speed_samples += len(vehicles)
        loop_s = clock() - loop_start
    finally:
        sumo.close()
    return {
        "departed": departed,
        "arrived": arrived,
        "collisions": collisions,
        "mean_speed": speed_sum / speed_samples if speed_samples else 0.0,
        "start_s": loop_start - t_start,
        "loop_s": loop_s,
        **t,
    }


def run_scenario(args: argparse.Namespace, sumo: Any) -> int:
    """The loop on a scenario of your own: SUMO started with the controller's command (your
    configuration, then the options bkpbs needs), stepped, closed; the episode's row printed."""
    steps = {"steps": args.steps} if args.steps_given else {}
    ctl = bkpbs.Controller(args.planner, sumocfg=args.sumocfg, alpha=args.alpha, seed=args.seed,
                           **steps)
    sumo.start(ctl.sumo_command)
    try:
        ctl.start(sumo)
        for _ in range(ctl.steps):
            sumo.simulationStep()
            ctl.step(sumo)
    finally:
        sumo.close()
    row = ctl.finish(out=args.out)
    print(
        f"{args.planner} via {sumo.__name__} on {row['scenario']}: α={args.alpha} seed={args.seed} "
        f"steps={row['steps']}: {row['inserted']} inserted ({row['inserted_cav']} CAVs), "
        f"{row['arrived']} arrived, {row['present']} still driving, {row['crashed']} crashed "
        f"({row['controllable_crashed']} controllable), regions {row['regions']}"
    )
    return 0


def net_override(args: argparse.Namespace) -> Dict[str, Any]:
    """The configuration override of ``--net``, if given."""
    return {"net_file": os.path.abspath(args.net)} if args.net else {}


def rust_timing(args: argparse.Namespace, out: str) -> Dict[str, float]:
    """The same episode in bkpbs's Rust runner; its timing.csv."""
    bkpbs.run_episode(args.planner, args.alpha, args.lam, args.seed, steps=args.steps, out=out,
                      **net_override(args))
    with open(os.path.join(out, "timing.csv"), newline="") as f:
        return {k: float(v) for k, v in next(csv.DictReader(f)).items()}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--planner", default="bk-pbs", choices=bkpbs.PLANNERS)
    p.add_argument("--alpha", type=float, default=0.5, help="CAV penetration α")
    p.add_argument("--lambda", dest="lam", type=float, default=3000.0, help="arrivals (veh/h)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--steps", type=int, help="steps of 0.2 s (default 400; with --sumocfg the "
                   "scenario's interval)")
    p.add_argument("--libsumo", action="store_true", help="libsumo in-process instead of traci")
    p.add_argument("--timing", action="store_true", help="per-step costs vs the Rust runner")
    p.add_argument("--files", help="directory for the scenario files (default: temporary)")
    p.add_argument("--net", metavar="FILE",
                   help="a SUMO merge network of your own (default: the shipped one)")
    p.add_argument("--gui", action="store_true", help="show the run in sumo-gui (traci only)")
    p.add_argument("--gui-delay", type=float, metavar="MS",
                   help="sumo-gui's pause per step (default: real time); implies --gui")
    p.add_argument("--sumocfg", metavar="FILE", help="a SUMO scenario of your own (its demand)")
    p.add_argument("--out", metavar="DIR", help="with --sumocfg: write the episode's files here")
    args = p.parse_args()
    args.steps_given = args.steps is not None
    args.steps = args.steps if args.steps_given else 400
    if args.sumocfg and (args.net or args.gui or args.timing or args.gui_delay is not None):
        sys.exit("error: --sumocfg runs your scenario as it is: without --net, --gui or --timing")
    if args.sumocfg:
        return run_scenario(args, import_sumo(args.libsumo))
    args.gui = args.gui or args.gui_delay is not None
    if args.gui and args.libsumo:
        sys.exit("error: --gui needs traci (sumo-gui is a process of its own), not --libsumo")
    if args.gui and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        sys.exit("error: no display for sumo-gui (DISPLAY is not set); on a machine without one "
                 "run under a virtual X server: xvfb-run -a python examples/traci_loop.py --gui")

    sumo = import_sumo(args.libsumo)
    with tempfile.TemporaryDirectory(prefix="bkpbs-traci-") as tmp:
        files = bkpbs.write_scenario(
            args.files or tmp, args.alpha, args.lam, args.seed, steps=args.steps,
            **net_override(args)
        )
        r = run(args, sumo, files)
        print(
            f"{args.planner} via {sumo.__name__}: α={args.alpha} λ={args.lam:g} seed={args.seed} "
            f"steps={args.steps}: {files['vehicles']} scheduled, {r['departed']} departed, "
            f"{r['arrived']} arrived, {r['collisions']} collisions, "
            f"mean speed {r['mean_speed']:.2f} m/s"
        )
        if args.timing:
            n = args.steps
            ms = {k: r[k] * 1e3 / n for k in ("sumo", "read", "plan", "apply", "loop_s")}
            rust = rust_timing(args, os.path.join(tmp, "rust"))
            print(f"per step (ms), {sumo.__name__} loop: total {ms['loop_s']:.3f} = SUMO step "
                  f"{ms['sumo']:.3f} + read {ms['read']:.3f} + plan {ms['plan']:.3f} + apply "
                  f"{ms['apply']:.3f} + rest; overhead beyond SUMO and planning: "
                  f"{ms['loop_s'] - ms['sumo'] - ms['plan']:.3f}; start {r['start_s']:.2f} s")
            plan = rust.get("plan_ms_total", float("nan")) / n
            print(f"per step (ms), Rust runner: total {rust['episode_ms_per_step']:.3f}, SUMO step "
                  f"{rust['sumo_ms_per_step']:.3f}, plan median {rust['plan_ms_median']:.3f}"
                  + (f", plan mean {plan:.3f}" if plan == plan else "")
                  + f"; wall {rust['wall_s'] * 1e3 / n:.3f} incl. start/close")
    return 0


if __name__ == "__main__":
    sys.exit(main())
