"""bkpbs: BK-PBS coordination of connected automated vehicles (CAVs) at a highway on-ramp merge.

The Rust core does the work; this package is a thin layer over it:

- :class:`Controller` plans one step for the vehicles a user's own TraCI or libsumo loop reads,
  and :func:`apply` sends its maneuvers back through that loop's module.
- :func:`run_episode` runs a whole episode in the core's loop (SUMO in-process, GIL released).
- :func:`write_scenario` / :func:`write_demand` write the network, vehicle types and demand
  for a Python loop; :class:`Campaign` and ``python -m bkpbs.campaign`` run experiment grids
  (locally or on Ray) into the directory layout ``bkpbs report`` reads.
- :func:`load_predictor` gives the planners' HDV predictor.
- ``bkpbs.gym`` (imported on its own; needs gymnasium, and pettingzoo for the multi-agent one):
  the merge scenario as a Gymnasium environment (``bkpbs/Merge-v0``) and a PettingZoo
  ``ParallelEnv``, stepped through the core.

Bad arguments raise :class:`BkpbsError` (a ``ValueError``); SUMO failures raise
:class:`SumoError` (a ``RuntimeError``).
"""

from ._bkpbs import (
    PLANNERS,
    SUMO_VERSION,
    BkpbsError,
    Campaign,
    CampaignTask,
    Controller,
    Maneuver,
    Predictor,
    SimulationBusyError,
    SumoError,
    __version__,
    config_toml,
    load_predictor,
    report,
    run_episode,
    write_demand,
    write_scenario,
)
from .sumo import Vehicle, apply, read_vehicles

__all__ = [
    "PLANNERS",
    "SUMO_VERSION",
    "BkpbsError",
    "Campaign",
    "CampaignTask",
    "Controller",
    "Maneuver",
    "Predictor",
    "SimulationBusyError",
    "SumoError",
    "Vehicle",
    "__version__",
    "apply",
    "config_toml",
    "load_predictor",
    "read_vehicles",
    "report",
    "run_episode",
    "write_demand",
    "write_scenario",
]
