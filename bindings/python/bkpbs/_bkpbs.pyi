"""Type stubs of the native module ``bkpbs._bkpbs`` (Rust, pyo3).

Kept in step with the module by ``tests/test_stubs.py``.
"""

import os
from pathlib import Path
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

_ConfigSource = Union[Mapping[str, Any], str, "os.PathLike[str]", None]
_PathArg = Union[str, "os.PathLike[str]"]

__version__: str
#: The SUMO version the module was built against and runs (a run against another libsumo is
#: refused); every summary's ``sumo_version``.
SUMO_VERSION: str
#: The planner names ``Controller`` and ``run_episode`` accept.
PLANNERS: List[str]
#: SUMO's ``speedMode`` and ``laneChangeMode`` of a commanded CAV, as the core sets them
#: (``bkpbs.sumo.apply`` switches each CAV to them once).
COMMANDED_MODES: Tuple[int, int]

class BkpbsError(ValueError):
    """Bad input: unknown planner, α outside [0, 1], unknown or invalid configuration key,
    malformed vehicle, bad campaign grid."""

class SumoError(RuntimeError):
    """SUMO failed to start or failed during an episode; the message is SUMO's."""

class SimulationBusyError(SumoError):
    """An episode is already running in this process (libsumo: one simulation per process)."""

class Maneuver:
    """What one CAV does during the next step."""

    #: Speed to command with ``setSpeed`` (m/s), already clamped to [0, v_max].
    @property
    def speed(self) -> float: ...
    #: ``None``, ``"left"`` or ``"right"``: start a lane change now.
    @property
    def lane_change(self) -> Optional[str]: ...
    #: Target lane index on the vehicle's current SUMO edge (its current lane without a lane
    #: change); ``None`` when that edge has no such lane.
    @property
    def sumo_lane_index(self) -> Optional[int]: ...

class Controller:
    """A core planner driven one step at a time by the caller's TraCI or libsumo loop.

    With ``sumocfg=`` (a SUMO configuration of the user's own) it is a whole episode on that
    scenario instead, one planner per merge region: start SUMO with ``sumo_command``, call
    ``start(traci)`` once, ``step(traci)`` after every ``simulationStep``, close SUMO, then
    ``finish(out=...)`` for the row and files of ``bkpbs episode --sumocfg``.
    """

    def __init__(
        self,
        planner: str = "bk-pbs",
        config: _ConfigSource = None,
        model: Optional[_PathArg] = None,
        net_file: Optional[_PathArg] = None,
        sumocfg: Optional[_PathArg] = None,
        **overrides: Any,
    ) -> None: ...
    @property
    def sumo_command(self) -> List[str]:
        """SUMO's command line: the scenario's configuration, then bkpbs's options."""
    @property
    def steps(self) -> int:
        """The episode's length in steps (the scenario's interval, or ``steps=``)."""
    def start(self, traci: Any) -> None:
        """Once SUMO runs, before its first step."""
    def step(self, traci: Any) -> None:
        """After each ``simulationStep``: books it, plans every region, commands the CAVs."""
    def finish(self, out: Optional[_PathArg] = None) -> Dict[str, Any]:
        """After SUMO is closed: the ``episode.csv`` row; its files into ``out`` if given."""
    def plan(
        self, vehicles: Iterable[Union[Mapping[str, Any], Any]], time: Optional[float] = None
    ) -> Dict[str, Maneuver]:
        """One ``Maneuver`` per CAV on the merge section, keyed by vehicle id.

        ``vehicles``: dicts (or objects such as ``bkpbs.Vehicle``) with ``id, type, angle,
        speed, acceleration, lane_index, lane_position, road_id`` and optionally ``x, y,
        lateral_offset, origin, desired_speed``, in SUMO's units as TraCI reports them.
        """
    @property
    def planner(self) -> str: ...
    @property
    def commands_cavs(self) -> bool: ...
    @property
    def dt(self) -> float: ...
    @property
    def v_max(self) -> float: ...
    def last_stats(self) -> Dict[str, int]: ...

_Pose = Tuple[float, float, float, float]

class Predictor:
    """An HDV predictor over the merge network's road frame (b_θ or constant speed)."""

    @property
    def name(self) -> str: ...
    def predict(
        self,
        vehicles: Iterable[Union[Mapping[str, Any], Any]],
        vehicle_id: str,
        horizon: Optional[int] = None,
        plans: Optional[Sequence[Sequence[_Pose]]] = None,
    ) -> List[float]:
        """Per-step probabilities (hazards) that HDV ``vehicle_id`` starts a lane change, from
        now until the change is predicted to start or the horizon ends. ``plans``: the
        ``(s, y, heading, speed)`` trajectories of higher-priority CAVs (conditioned model)."""
    def trajectory(
        self,
        vehicles: Iterable[Union[Mapping[str, Any], Any]],
        vehicle_id: str,
        horizon: Optional[int] = None,
        plans: Optional[Sequence[Sequence[_Pose]]] = None,
    ) -> List[_Pose]:
        """Predicted ``(s, y, heading, speed)`` at steps 0 … horizon."""

class MergeEnvCore:
    """The merge scenario stepped one decision at a time (under ``bkpbs.gym``)."""

    OBS_DIM: int
    def __init__(
        self,
        agents: str = "single",
        alpha: float = 0.5,
        lam: Optional[float] = None,
        config: Optional[Union[Mapping[str, Any], str, "os.PathLike[str]"]] = None,
        sumocfg: Optional[Union[str, "os.PathLike[str]"]] = None,
        **overrides: Any,
    ) -> None:
        """``agents``: "single" (one CAV among HDVs) or "all" (every CAV); ``lam`` 3000 veh/h
        unless given; ``sumocfg``: a SUMO scenario of your own instead (no ``lam``)."""
    def reset(self, seed: int) -> None:
        """Starts a new episode (ending the running one) and runs to the first agent's step."""
    def agents(self) -> List[str]: ...
    def possible_agents(self) -> List[str]: ...
    def observations(self) -> bytes:
        """float32, agents × OBS_DIM, row-major."""
    def masks(self) -> bytes:
        """uint8, agents × 6 (1 = allowed)."""
    def step(self, actions: List[int]) -> Tuple[List[Tuple[str, float]], List[str], List[str], bool]:
        """(rewards, terminated agents, truncated agents, done)."""
    def render_rgb(self, width: int = 600, height: int = 150) -> bytes:
        """height × width × 3 RGB bytes of the current step."""
    def summary(self) -> Optional[Dict[str, Any]]:
        """The finished episode's ``episode.csv`` values (as ``run_episode`` returns them), once
        it has ended or been closed (its agents idled to the end); ``None`` before."""
    def close(self) -> None: ...
    @staticmethod
    def feature_names() -> List[str]: ...
    @staticmethod
    def action_names() -> List[str]: ...

class CampaignTask:
    """One unfinished episode of a campaign; picklable."""

    @staticmethod
    def from_json(text: str) -> "CampaignTask": ...
    def to_json(self) -> str: ...
    @property
    def position(self) -> int: ...
    @property
    def planner(self) -> str: ...
    @property
    def alpha(self) -> float: ...
    @property
    def lam(self) -> float: ...
    @property
    def seed(self) -> int: ...
    @property
    def scenario(self) -> Optional[Path]:
        """The scenario of your own the episode runs (its ``.sumocfg``), ``None`` on the paper's demand."""
    @property
    def dir(self) -> Path: ...
    def run(self) -> Optional[str]:
        """Runs the episode in this process; ``None`` when done, else the error message."""
    def inputs(self, base: Optional[_PathArg] = None) -> List[Path]:
        """The files the episode reads, absolute (relative ones resolved against ``base``,
        default the working directory): its ``.sumocfg`` and the files that names, model,
        calibration and policy files."""
    def run_portable(
        self, scratch: _PathArg, base: _PathArg, inputs: Sequence[Tuple[_PathArg, bytes]]
    ) -> Tuple[Optional[str], List[Tuple[str, bytes]]]:
        """Runs the episode here against copies of ``inputs`` (the files ``inputs(base)``
        listed where the campaign runs) written below ``scratch``; ``(None, files)`` with the
        cell's files as ``(relative path, bytes)``, or ``(error, [])``."""
    def store(self, files: Sequence[Tuple[_PathArg, bytes]]) -> None:
        """Puts the files ``run_portable`` returned into the cell directory, replacing its
        earlier files, ``episode.csv`` last."""
    def record_failure(self, message: str) -> None: ...

class Campaign:
    """A planners × α × λ × seeds campaign in directory ``out`` (``bkpbs campaign``'s layout); with
    ``sumocfg`` (a list or comma-separated string of ``.sumocfg`` files) planners × scenarios × α ×
    seeds over scenarios of your own, as ``bkpbs campaign --sumocfg``."""

    def __init__(
        self,
        out: _PathArg,
        *,
        config: Optional[_PathArg] = None,
        planners: Union[str, Sequence[str], None] = None,
        alphas: Union[str, Sequence[float], None] = None,
        lambdas: Union[str, Sequence[float], None] = None,
        seeds: Optional[int] = None,
        seed_base: Optional[int] = None,
        steps: Optional[int] = None,
        shard: Optional[str] = None,
        sumocfg: Union[str, Sequence[_PathArg], None] = None,
    ) -> None: ...
    @property
    def out(self) -> Path: ...
    @property
    def grid_size(self) -> int: ...
    @property
    def shard(self) -> str: ...
    def settings_toml(self) -> str: ...
    def cells(self) -> List[Dict[str, Any]]:
        """Every cell in grid order: position, planner, alpha, lambda, seed, dir (over scenarios:
        position, planner, scenario, alpha, seed, dir)."""
    def prepare(self) -> List[CampaignTask]:
        """Writes ``campaign.toml`` and returns the unfinished episodes of the shard."""
    def collect(self) -> Dict[str, Any]:
        """Writes the collected CSV files; returns grid, collected, failed, episodes_csv."""

def run_episode(
    planner: str,
    alpha: float,
    lam: Optional[float] = None,
    seed: int = 0,
    *,
    config: _ConfigSource = None,
    out: Optional[_PathArg] = None,
    sumocfg: Optional[_PathArg] = None,
    **overrides: Any,
) -> Dict[str, Any]:
    """Runs one episode in the core's loop; returns the ``episode.csv`` row as a dict of the values
    it is written from: ``str``, ``int`` and full-precision ``float`` (not rounded to the CSV's
    decimals), ``None`` for an empty cell. ``lam`` defaults to the configuration's λ. With
    ``sumocfg`` the episode runs that SUMO scenario of your own instead of the paper's demand
    (no ``lam``; its ``begin``–``end`` interval unless ``steps=`` shortens it), as
    ``bkpbs episode --sumocfg`` does, and the row is that scenario ``episode.csv``'s."""

def write_demand(
    out: _PathArg,
    alpha: float = 0.5,
    lam: float = 3000.0,
    seed: int = 0,
    *,
    config: _ConfigSource = None,
    **overrides: Any,
) -> int:
    """Writes the episode's demand as a SUMO route file; returns the number of vehicles."""

def write_scenario(
    dir: _PathArg,
    alpha: float = 0.5,
    lam: float = 3000.0,
    seed: int = 0,
    *,
    config: _ConfigSource = None,
    **overrides: Any,
) -> Dict[str, Any]:
    """Writes net, vehicle types and demand; returns their paths, ``sumo_args``, ``dt``,
    ``steps`` and ``vehicles``."""

def config_toml(config: _ConfigSource = None, **overrides: Any) -> str:
    """The whole configuration as TOML after ``config`` and overrides."""

def report(dirs: Sequence[_PathArg], out: Optional[_PathArg] = None) -> str:
    """Tables and figures of campaign directories (``bkpbs report``); returns the Markdown."""

def load_predictor(
    path: Optional[_PathArg] = None, *, config: _ConfigSource = None, **overrides: Any
) -> Predictor:
    """The planners' HDV predictor: ``path`` is a b_θ model file (JSON); without it, the one
    the configuration's ``predictor.kind`` selects (``"learned"`` or ``"constant"``). A model
    trained under another step length than the configuration's ``scenario.dt`` (its
    ``trained_on`` record) raises ``BkpbsError``."""
