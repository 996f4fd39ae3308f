"""The episode metrics recomputed from SUMO's own outputs, with no project code doing the arithmetic.

Each case runs `bkpbs episode` with SUMO's `--fcd-output`, `--tripinfo-output` and
`--collision-output` switched on (through `[sumo] extra_args`) and `bkpbs demand` for the schedule
the episode was drawn from. Everything below is then recomputed from those XML files alone: per
vehicle the insertion time, entry delay, route distance, free-flow time t*, arrival time
(interpolated within the last step the way the README states), travel time, time in the network,
delay and crash time; per episode the counts, collision rates, mean delays, throughput and mean
speed; and every collision. The CSV files must agree within 0.01 s (counts exactly).

Conventions the oracle takes from the README, not from the code: every time is on SUMO's clock (the
label SUMO's outputs give a state); t* is the free-flow time from the drawn insertion speed at
`free_flow_accel` up to `v_max`; a vehicle's delay counts from its scheduled departure; the frame
lanes are 0 = ramp / acceleration lane, 1 and 2 = the main road's right and left lanes.
"""

from __future__ import annotations

import csv
import math
import subprocess
import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path
from typing import Dict, List, Tuple

import pytest

from conftest import REPO

DT = 0.2
STEPS = 400
V_MAX = 35.0
FREE_FLOW_ACCEL = 3.0
TOLERANCE_S = 0.01

# Two HDVs staged to collide: B is inserted without SUMO's insertion checks 3 m behind A, which
# stands; SUMO reports the collision one step later. Covers the HDV-HDV path of the metrics.
STAGED_HDV_COLLISION = """<routes>
    <route id="staged" edges="main_in acc main_out"/>
    <vehicle id="staged.a" type="hdv" route="staged" depart="2" departLane="0" departPos="60" departSpeed="0"/>
    <vehicle id="staged.b" type="hdv" route="staged" depart="2" departLane="0" departPos="57" departSpeed="20" insertionChecks="none"/>
</routes>
"""

CASES = [
    # planner, alpha, lambda, seed, staged HDV-HDV collision
    ("idm-mobil", 0.5, 3000, 3, True),
    ("idm-mobil", 0.4, 2500, 5, False),
    ("bk-mastar", 0.8, 3000, 1, False),
    ("bk-pbs", 0.8, 2500, 2, True),
    ("sumo", 0.6, 2500, 4, False),
]

# Road-frame lane of SUMO lane index 0 on each edge.
LANE_OFFSET = {"main_in": 1, "ramp": 0, "acc": 0, "main_out": 1}


def lane_lengths(net: Path) -> Dict[str, float]:
    """Length of each edge's lane 0, as the network file says."""
    out = {}
    for lane in ET.parse(net).getroot().iter("lane"):
        if lane.get("id", "").endswith("_0"):
            out[lane.get("id")[:-2]] = float(lane.get("length"))
    return out


def free_flow_time(distance: float, v0: float) -> float:
    """Accelerate at FREE_FLOW_ACCEL from v0 up to V_MAX, then cruise."""
    if distance <= 0:
        return 0.0
    v0 = max(0.0, min(v0, V_MAX))
    d_acc = (V_MAX**2 - v0**2) / (2 * FREE_FLOW_ACCEL)
    if d_acc >= distance:
        return (-v0 + math.sqrt(v0**2 + 2 * FREE_FLOW_ACCEL * distance)) / FREE_FLOW_ACCEL
    return (V_MAX - v0) / FREE_FLOW_ACCEL + (distance - d_acc) / V_MAX


def run_case(cli: Path, tmp: Path, planner: str, alpha: float, lam: float, seed: int, staged: bool) -> Dict[str, Path]:
    files = {k: tmp / f"{k}.xml" for k in ("fcd", "trip", "col")}
    extra = [
        "--fcd-output", str(files["fcd"]),
        "--tripinfo-output", str(files["trip"]),
        "--tripinfo-output.write-unfinished", "true",
        "--collision-output", str(files["col"]),
        "--precision", "6",
    ]
    lines = ["[sumo]", "extra_args = [" + ", ".join(f'"{a}"' for a in extra) + "]"]
    if staged:
        staged_file = tmp / "staged.rou.xml"
        staged_file.write_text(STAGED_HDV_COLLISION)
        lines.append(f'additional_files = ["{staged_file}"]')
    cfg = tmp / "oracle.toml"
    cfg.write_text("\n".join(lines) + "\n")
    cell = ["--alpha", str(alpha), "--lambda", str(lam), "--seed", str(seed), "--config", str(cfg)]
    out = tmp / "out"
    for args in (["episode", "--planner", planner, *cell, "--out", str(out)], ["demand", *cell, "--out", str(tmp / "demand.rou.xml")]):
        r = subprocess.run([str(cli), *args], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
    files.update(out=out, demand=tmp / "demand.rou.xml")
    return files


def kind(type_id: str) -> str:
    """The vehicle type without SUMO's per-vehicle suffix (`hdv@main.3` once a vehicle's own
    parameters were changed)."""
    return type_id.split("@")[0]


def read_fcd(path: Path) -> Tuple[Dict[str, List[dict]], List[float]]:
    """Per vehicle its states in time order; and every speed of every state."""
    states: Dict[str, List[dict]] = defaultdict(list)
    speeds: List[float] = []
    for ts in ET.parse(path).getroot().iter("timestep"):
        t = float(ts.get("time"))
        for v in ts.iter("vehicle"):
            edge, index = v.get("lane").rsplit("_", 1)
            s = {"t": t, "edge": edge, "index": int(index), "pos": float(v.get("pos")),
                 "speed": float(v.get("speed")), "type": kind(v.get("type"))}
            states[v.get("id")].append(s)
            speeds.append(s["speed"])
    return states, speeds


def expected(files: Dict[str, Path]) -> Tuple[Dict[str, dict], dict, List[dict]]:
    """Per-vehicle figures, the episode's aggregates and the collisions, from SUMO's files alone."""
    lengths = lane_lengths(REPO / "sumo_net" / "merge.net.xml")
    demand_root = ET.parse(files["demand"]).getroot()
    routes = {r.get("id"): r.get("edges").split() for r in demand_root.iter("route")}
    routes["staged"] = routes["main"]
    scheduled = {v.get("id"): v for v in demand_root.iter("vehicle")}
    states, speeds = read_fcd(files["fcd"])
    trips = {t.get("id"): t for t in ET.parse(files["trip"]).getroot().iter("tripinfo")}
    collisions = [c.attrib for c in ET.parse(files["col"]).getroot().iter("collision")]
    # SUMO reports a colliding pair again each step until the runner has removed it: the first report counts.
    first_collisions, crash_time, seen = [], {}, set()
    for c in collisions:
        pair = (c["collider"], c["victim"])
        if pair in seen or c["collider"] in crash_time or c["victim"] in crash_time:
            continue
        seen.add(pair)
        first_collisions.append(c)
        for vid in pair:
            crash_time.setdefault(vid, float(c["time"]))
    cav_in = defaultdict(bool)
    for c in first_collisions:
        involved_cav = "cav" in (kind(c["colliderType"]), kind(c["victimType"]))
        cav_in[c["collider"]] |= involved_cav
        cav_in[c["victim"]] |= involved_cav

    per_vehicle = {}
    for vid, ss in states.items():
        first, last = ss[0], ss[-1]
        plan = scheduled.get(vid)
        sched = float(plan.get("depart")) if plan is not None else first["t"]
        drawn = float(plan.get("departSpeed")) if plan is not None else 0.0
        route = routes[plan.get("route")] if plan is not None else routes["main"]
        distance = sum(lengths[e] for e in route) - first["pos"]
        t_star = free_flow_time(distance, drawn)
        rec = {
            "type": first["type"], "scheduled_depart_s": sched, "insert_time_s": first["t"],
            "entry_delay_s": max(first["t"] - sched, 0.0),
            "insert_lane": LANE_OFFSET[first["edge"]] + first["index"],
            "insert_speed_mps": first["speed"], "distance_m": distance, "t_star_s": t_star,
            "crash_time_s": crash_time.get(vid), "arrival_time_s": None,
        }
        trip = trips.get(vid)
        if vid in crash_time:
            rec["outcome"] = "crashed"
            rec["controllable_crash"] = cav_in[vid]
        elif trip is not None and float(trip.get("arrival")) >= 0:
            assert last["edge"] == "main_out", (vid, last)
            left_at = float(trip.get("arrival"))
            remaining = max(lengths["main_out"] - last["pos"], 0.0)
            crossing = min(last["t"] + remaining / last["speed"], left_at) if last["speed"] > 0.1 else left_at
            rec["outcome"] = "arrived"
            rec["arrival_time_s"] = max(crossing, last["t"])
        else:
            rec["outcome"] = "present"
        if rec["arrival_time_s"] is not None:
            a = rec["arrival_time_s"]
            rec.update(travel_time_s=a - sched, time_in_network_s=a - first["t"], delay_s=a - sched - t_star)
        per_vehicle[vid] = rec

    def mean_delay(kind=None):
        ds = [r["delay_s"] for r in per_vehicle.values() if r["outcome"] == "arrived" and kind in (None, r["type"])]
        return sum(ds) / len(ds) if ds else None

    inserted = len(per_vehicle)
    outcomes = [r["outcome"] for r in per_vehicle.values()]
    controllable = sum(1 for r in per_vehicle.values() if r["outcome"] == "crashed" and r["controllable_crash"])
    aggregates = {
        "inserted": inserted,
        "inserted_cav": sum(1 for r in per_vehicle.values() if r["type"] == "cav"),
        "arrived": outcomes.count("arrived"),
        "crashed": outcomes.count("crashed"),
        "present": outcomes.count("present"),
        "controllable_crashed": controllable,
        "controllable_collision_rate": controllable / inserted if inserted else 0.0,
        "hdv_collisions": sum(1 for c in first_collisions if kind(c["colliderType"]) == kind(c["victimType"]) == "hdv"),
        "hdv_crashed": outcomes.count("crashed") - controllable,
        "mean_delay_s": mean_delay(),
        "mean_delay_cav_s": mean_delay("cav"),
        "mean_delay_hdv_s": mean_delay("hdv"),
        "throughput_veh_h": outcomes.count("arrived") / (STEPS * DT / 3600),
        "mean_speed_mps": sum(speeds) / len(speeds),
    }
    return per_vehicle, aggregates, first_collisions


def read_csv(path: Path) -> List[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def close(a, b, tol=TOLERANCE_S) -> bool:
    if a is None or b in ("", None):
        return a is None and b in ("", None)
    return abs(a - float(b)) <= tol


TIME_COLUMNS = ["scheduled_depart_s", "insert_time_s", "entry_delay_s", "t_star_s", "arrival_time_s",
                "travel_time_s", "time_in_network_s", "delay_s", "crash_time_s"]


@pytest.mark.parametrize("planner,alpha,lam,seed,staged", CASES)
def test_metrics_agree_with_sumos_own_outputs(cli, tmp_path, planner, alpha, lam, seed, staged):
    files = run_case(cli, tmp_path, planner, alpha, lam, seed, staged)
    per_vehicle, aggregates, collisions = expected(files)
    rows = {r["id"]: r for r in read_csv(files["out"] / "vehicles.csv")}
    assert set(rows) == set(per_vehicle), "the same vehicles"
    for vid, exp in per_vehicle.items():
        row = rows[vid]
        assert row["outcome"] == exp["outcome"], (vid, row, exp)
        assert int(row["insert_lane"]) == exp["insert_lane"], (vid, row, exp)
        assert close(exp["distance_m"], row["distance_m"], 0.01), (vid, row, exp)
        for col in TIME_COLUMNS:
            assert close(exp.get(col), row[col]), f"{vid} {col}: SUMO says {exp.get(col)}, the CSV {row[col]}"
        if exp["outcome"] == "crashed":
            assert (row["controllable_crash"] == "true") == exp["controllable_crash"], (vid, row)
    summary = read_csv(files["out"] / "episode.csv")[0]
    for key, value in aggregates.items():
        if isinstance(value, int):
            assert int(summary[key]) == value, (key, summary[key], value)
        else:
            assert close(value, summary[key], 1e-4 if key == "mean_speed_mps" else TOLERANCE_S), (key, summary[key], value)
    got = read_csv(files["out"] / "collisions.csv")
    assert [(c["collider"], c["victim"]) for c in got] == [(c["collider"], c["victim"]) for c in collisions]
    for c, e in zip(got, collisions):
        assert close(float(e["time"]), c["time_s"]) and c["lane"] == e["lane"], (c, e)
    if staged:
        assert aggregates["hdv_collisions"] >= 1 and int(summary["hdv_collisions"]) >= 1
        assert rows["staged.a"]["outcome"] == "crashed" and rows["staged.a"]["controllable_crash"] == "false"
