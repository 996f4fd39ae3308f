"""Glue between a user's TraCI or libsumo loop and :class:`bkpbs.Controller`.

Everything here is plain TraCI I/O through the module the caller passes (``traci``, ``libsumo``
or a ``traci`` connection): reading the vehicles the controller needs, and issuing the speed and
lane-change commands of its maneuvers. What to do is decided in Rust.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, MutableSet, Optional

from ._bkpbs import COMMANDED_MODES, Maneuver


@dataclass
class Vehicle:
    """One vehicle as TraCI reports it (SUMO's units: m, degrees with 0 = north clockwise, m/s).

    ``Controller.plan`` accepts these or dicts with the same keys.
    """

    id: str
    type: str
    angle: float
    speed: float
    acceleration: float
    lane_index: int
    lane_position: float
    road_id: str
    x: Optional[float] = None
    y: Optional[float] = None
    #: ``getLateralLanePosition`` (m, positive left); non-zero during a lane change.
    lateral_offset: Optional[float] = None
    #: ``getLateralSpeed`` (m/s, positive left): with it the heading is the direction of motion,
    #: without it SUMO's drawn ``angle``, which SUMO versions draw differently.
    lateral_speed: Optional[float] = None
    #: ``"main"`` or ``"ramp"``; default: from the id (``main.N``/``ramp.N``) or the first road.
    origin: Optional[str] = None
    #: Default: v_max for CAVs, the current speed for HDVs.
    desired_speed: Optional[float] = None


def _variables(traci_module: Any) -> Dict[str, int]:
    tc = traci_module.constants
    return {
        "type": tc.VAR_TYPE,
        "position": tc.VAR_POSITION,
        "angle": tc.VAR_ANGLE,
        "speed": tc.VAR_SPEED,
        "acceleration": tc.VAR_ACCELERATION,
        "lane_index": tc.VAR_LANE_INDEX,
        "lane_position": tc.VAR_LANEPOSITION,
        "road_id": tc.VAR_ROAD_ID,
        "lateral_offset": tc.VAR_LANEPOSITION_LAT,
        "lateral_speed": tc.VAR_SPEED_LAT,
    }


def read_vehicles(traci_module: Any) -> List[Dict[str, Any]]:
    """The vehicles in the network as :meth:`bkpbs.Controller.plan` takes them.

    Call once per step, after ``simulationStep`` and after removing any vehicle (of a
    collision, say). Only vehicles SUMO still knows (``vehicle.getIDList()``) are returned:
    the step's subscription results still hold a vehicle removed since, and it is dropped and
    unsubscribed (libsumo would otherwise fail the next step on it); arrived vehicles are gone
    from the results already. Each vehicle not yet subscribed (departed in the step) gets a
    subscription to the variables the controller needs, so all are read in one exchange.
    """
    codes = _variables(traci_module)
    vehicle = traci_module.vehicle
    known = vehicle.getIDList()
    known_set = set(known)
    # traci returns its live dict, which subscribe and unsubscribe below change: copy first.
    results = dict(vehicle.getAllSubscriptionResults())
    for vid in [v for v in results if v not in known_set]:
        _unsubscribe(vehicle, vid)
        del results[vid]
    new = [v for v in known if v not in results]
    if new:
        wanted = list(codes.values())
        for vid in new:
            vehicle.subscribe(vid, wanted)
            results[vid] = vehicle.getSubscriptionResults(vid)
    out = []
    for vid, r in results.items():
        x, y = r[codes["position"]]
        out.append(
            {
                "id": vid,
                "type": r[codes["type"]],
                "x": x,
                "y": y,
                "angle": r[codes["angle"]],
                "speed": r[codes["speed"]],
                "acceleration": r[codes["acceleration"]],
                "lane_index": r[codes["lane_index"]],
                "lane_position": r[codes["lane_position"]],
                "road_id": r[codes["road_id"]],
                "lateral_offset": r[codes["lateral_offset"]],
                "lateral_speed": r[codes["lateral_speed"]],
            }
        )
    return out


#: CAVs already switched to commanded mode, per TraCI module or connection (by identity for
#: objects that take no weak reference).
_COMMANDED: "weakref.WeakKeyDictionary[Any, set]" = weakref.WeakKeyDictionary()
_COMMANDED_BY_ID: Dict[int, set] = {}


def _commanded(traci_module: Any) -> MutableSet[str]:
    try:
        return _COMMANDED.setdefault(traci_module, set())
    except TypeError:
        return _COMMANDED_BY_ID.setdefault(id(traci_module), set())


def apply(
    maneuvers: Mapping[str, Maneuver],
    traci_module: Any,
    dt: float = 0.2,
    commanded: Optional[MutableSet[str]] = None,
) -> None:
    """Sends maneuvers to SUMO as the episode runner does.

    Each CAV is first switched to commanded mode (``COMMANDED_MODES``, the core's: speed mode 0
    and lane-change mode 0, SUMO's own checks off, the controller alone decides), then gets ``setSpeed`` every step and
    ``changeLane(id, sumo_lane_index, dt)`` when its maneuver starts a lane change.
    ``commanded`` is the set of vehicles already switched (default: one per ``traci_module``);
    vehicles absent from ``maneuvers`` are dropped from it, so a reused id is switched again.
    A vehicle SUMO no longer knows (removed or arrived since it was read) is skipped, dropped
    from ``commanded`` and unsubscribed; any other error of a command is raised.
    """
    seen = commanded if commanded is not None else _commanded(traci_module)
    vehicle = traci_module.vehicle
    for vid, m in maneuvers.items():
        try:
            if vid not in seen:
                speed_mode, lane_change_mode = COMMANDED_MODES
                vehicle.setSpeedMode(vid, speed_mode)
                vehicle.setLaneChangeMode(vid, lane_change_mode)
                seen.add(vid)
            vehicle.setSpeed(vid, m.speed)
            if m.lane_change is not None and m.sumo_lane_index is not None:
                vehicle.changeLane(vid, m.sumo_lane_index, dt)
        except Exception:
            if not _vanished(vehicle, vid):
                raise
            seen.discard(vid)
    for vid in [v for v in seen if v not in maneuvers]:
        seen.discard(vid)


def _vanished(vehicle: Any, vid: str) -> bool:
    """Whether SUMO no longer knows ``vid`` (removed or arrived); then it is also unsubscribed
    so that the next step does not fail on it. ``False`` when even that cannot be asked."""
    try:
        if vid in vehicle.getIDList():
            return False
    except Exception:
        return False
    _unsubscribe(vehicle, vid)
    return True


def _unsubscribe(vehicle: Any, vid: str) -> None:
    """Ends the subscription of a vehicle SUMO no longer knows, if it still has one."""
    try:
        vehicle.unsubscribe(vid)
    except Exception:
        pass  # never subscribed, or SUMO dropped the subscription itself
