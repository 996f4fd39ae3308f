"""Gymnasium and PettingZoo environments of the merge scenario, stepped through the Rust core.

- :class:`MergeEnv` (registered as ``bkpbs/Merge-v0``): one CAV among HDVs, as the paper trains
  its RL-PPO baseline; observation = the ego and its 14 nearest vehicles in the road frame
  (``MergeEnv.feature_names``), action = one of the six motion primitives
  (``MergeEnv.action_names``), reward as ``bkpbs train-rl``'s (the guide's Python and RL chapter).
- :class:`MergeParallelEnv`: a PettingZoo ``ParallelEnv`` with every CAV an agent (the shared
  policy of the paper's test set-up); agents appear when inserted and leave when they arrive
  (truncated) or crash (terminated).

Each step's ``info`` holds the agent's ``action_mask`` (1 = allowed by the lane-change rules).
An action must be an integer in ``range(6)`` (a fractional or out-of-range one is a
``ValueError``); a masked-out action is a ``ValueError`` too, unless the environment is made with
``masked_actions="idle"``, which executes it as idle (for learners that do not mask, such as
Stable-Baselines3's PPO, and for Gymnasium's ``check_env``, which samples actions at random).

With ``sumocfg=FILE`` either environment runs a SUMO scenario of your own instead of the paper's
merge (no ``lam``: it brings its own demand), as ``bkpbs episode --sumocfg`` runs it: every merge
region's CAVs are the agents of one step, each observed in its own region's frame, and SUMO
drives them outside the regions. :class:`MergeEnv`'s agent is the first CAV of the scenario's
draw (``alpha`` or ``cav_types=[...]``) that departs after the warm-up on a route through a
region, every other vehicle an HDV; :class:`MergeParallelEnv`'s ``possible_agents`` grows as
the scenario's flows bring CAVs. A scenario's episode is its whole interval: ``steps=N``
shortens it (closing or resetting an environment runs the rest of the episode to its end).

``reset(seed=s)`` alone decides what follows, whatever ran before. A demand seed whose episode
never has a controllable CAV is skipped: the next seed is tried, and ``info["demand_seed"]``
says which seed the episode runs. SUMO runs in-process (libsumo): one environment per process
at a time; use vectorised environments with subprocesses for more.
"""

from __future__ import annotations

import functools
from typing import Any, Dict, List, Optional, Tuple

import gymnasium
import numpy as np
from gymnasium import spaces

from ._bkpbs import MergeEnvCore

try:  # PettingZoo is needed only for the multi-agent environment.
    from pettingzoo import ParallelEnv as _ParallelBase
except ImportError:  # pragma: no cover - exercised only without pettingzoo
    _ParallelBase = object

OBS_DIM: int = MergeEnvCore.OBS_DIM
N_ACTIONS: int = len(MergeEnvCore.action_names())
# How many demand seeds a reset tries for one with a controllable CAV before it gives up (on a
# scenario of your own, whose every try runs the scenario to its end, fewer).
MAX_SKIPPED_SEEDS = 100
MAX_SKIPPED_SCENARIO_SEEDS = 3
# Every feature is scaled by a fixed constant and clipped well inside this range.
OBS_BOUND = 4.0


def _observation_space() -> spaces.Box:
    return spaces.Box(-OBS_BOUND, OBS_BOUND, shape=(OBS_DIM,), dtype=np.float32)


def _check_render_mode(mode: Optional[str]) -> None:
    if mode not in (None, "rgb_array"):
        raise ValueError(f"render_mode {mode!r}: only 'rgb_array' is supported")


def _check_masked_actions(policy: str) -> None:
    if policy not in ("raise", "idle"):
        raise ValueError(f"masked_actions {policy!r}: use 'raise' or 'idle'")


def _action_index(action: Any, mask: np.ndarray, agent: Any, masked_actions: str) -> int:
    """The primitive index of ``action`` for ``agent``, checked: an integer (a Python or numpy
    integer, or a one-element integer array) in range, and allowed by ``mask`` unless masked
    actions are executed as idle."""
    value = action
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(()).item() if np.issubdtype(value.dtype, np.integer) else value
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"action {action!r} for agent {agent}: not an integer primitive index")
    index = int(value)
    if not 0 <= index < N_ACTIONS:
        raise ValueError(f"action {index} for agent {agent}: not one of the {N_ACTIONS} primitives")
    if not mask[index]:
        if masked_actions == "idle":
            return MergeEnvCore.action_names().index("idle")
        name = MergeEnvCore.action_names()[index]
        raise ValueError(
            f"action {index} ({name}) for agent {agent} is masked out by the lane-change rules "
            "(info['action_mask']); make the environment with masked_actions='idle' to run it as idle"
        )
    return index


def _reset_to_an_agent(core: "_Core", seed: int) -> Tuple[int, List[str], np.ndarray, np.ndarray]:
    """Resets ``core`` with demand seed ``seed``, or the next seeds if an episode never has a
    controllable CAV; the seed used and the first step's agents, observations and masks."""
    tries = MAX_SKIPPED_SCENARIO_SEEDS if core.scenario else MAX_SKIPPED_SEEDS
    for demand_seed in range(seed, seed + tries):
        core.env.reset(demand_seed)
        ids, obs, masks = core.arrays()
        if ids:
            return demand_seed, ids, obs, masks
    hint = "raise alpha, name cav_types" if core.scenario else "raise alpha or lam"
    raise RuntimeError(
        f"demand seeds {seed}..{seed + tries - 1} all give episodes without a "
        f"controllable CAV: {hint}, or lengthen steps"
    )


class _Core:
    """The core environment's current step as numpy arrays."""

    def __init__(self, agents: str, alpha: float, lam: Optional[float], config: Any,
                 sumocfg: Any, overrides: Dict[str, Any]):
        self.env = MergeEnvCore(agents, alpha, lam, config, sumocfg, **overrides)
        self.scenario = sumocfg is not None

    def arrays(self) -> Tuple[List[str], np.ndarray, np.ndarray]:
        ids = self.env.agents()
        obs = np.frombuffer(self.env.observations(), dtype="<f4").reshape(len(ids), OBS_DIM)
        masks = np.frombuffer(self.env.masks(), dtype=np.uint8).reshape(len(ids), N_ACTIONS)
        return ids, obs.astype(np.float32), masks.astype(np.int8)

    def frame(self, width: int, height: int) -> np.ndarray:
        return np.frombuffer(self.env.render_rgb(width, height), dtype=np.uint8).reshape(height, width, 3)


class MergeEnv(gymnasium.Env):
    """One CAV (the first inserted after a 10 s warm-up) among HDVs on the merge section, or on
    the merges of a scenario of your own (``sumocfg=``)."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 5}
    feature_names = MergeEnvCore.feature_names()
    action_names = MergeEnvCore.action_names()

    def __init__(
        self,
        alpha: float = 0.5,
        lam: Optional[float] = None,
        config: Any = None,
        render_mode: Optional[str] = None,
        render_size: Tuple[int, int] = (600, 150),
        masked_actions: str = "raise",
        sumocfg: Any = None,
        **overrides: Any,
    ):
        _check_render_mode(render_mode)
        _check_masked_actions(masked_actions)
        self.render_mode, self.render_size = render_mode, render_size
        self.masked_actions = masked_actions
        self.observation_space = _observation_space()
        self.action_space = spaces.Discrete(N_ACTIONS)
        self._core = _Core("single", alpha, lam, config, sumocfg, overrides)
        self._obs = np.zeros(OBS_DIM, dtype=np.float32)
        self._mask = np.ones(N_ACTIONS, dtype=np.int8)
        self._ego: Optional[str] = None
        self._ended = True

    def _read(self) -> Dict[str, Any]:
        ids, obs, masks = self._core.arrays()
        if ids:
            self._obs, self._mask = obs[0], masks[0]
        return {"action_mask": self._mask, "agent": self._ego}

    def reset(self, *, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None):
        super().reset(seed=seed)
        demand_seed = int(self.np_random.integers(0, 2**31 - 1)) if seed is None else int(seed)
        used, ids, obs, masks = _reset_to_an_agent(self._core, demand_seed)
        self._ego, self._obs, self._mask, self._ended = ids[0], obs[0], masks[0], False
        info = {"action_mask": self._mask, "agent": self._ego, "demand_seed": used}
        return self._obs.copy(), info

    def step(self, action):
        if self._ended:
            raise RuntimeError("the episode has ended: call reset() first")
        index = _action_index(action, self._mask, self._ego, self.masked_actions)
        rewards, terminated, truncated, done = self._core.env.step([index])
        reward = float(sum(r for _, r in rewards))
        ended = bool(terminated) or bool(truncated) or done
        info = self._read() if not ended else {"action_mask": self._mask, "agent": self._ego}
        if ended:
            self._ended = True
            info["episode_summary"] = self._core.env.summary()
        return self._obs.copy(), reward, bool(terminated), ended and not terminated, info

    def render(self):
        if self.render_mode == "rgb_array":
            return self._core.frame(*self.render_size)
        return None

    def close(self):
        self._core.env.close()


class MergeParallelEnv(_ParallelBase):
    """Every CAV an agent, all acting at once (PettingZoo ``ParallelEnv``), on the merge
    section or on every merge of a scenario of your own (``sumocfg=``)."""

    metadata = {"name": "bkpbs_merge_v0", "render_modes": ["rgb_array"], "render_fps": 5}

    def __init__(
        self,
        alpha: float = 0.5,
        lam: Optional[float] = None,
        config: Any = None,
        render_mode: Optional[str] = None,
        render_size: Tuple[int, int] = (600, 150),
        masked_actions: str = "raise",
        sumocfg: Any = None,
        **overrides: Any,
    ):
        _check_render_mode(render_mode)
        _check_masked_actions(masked_actions)
        self.render_mode, self.render_size = render_mode, render_size
        self.masked_actions = masked_actions
        self._core = _Core("all", alpha, lam, config, sumocfg, overrides)
        self._rng = np.random.default_rng()
        self.agents: List[str] = []
        self.possible_agents: List[str] = []
        self._last_obs: Dict[str, np.ndarray] = {}
        self._masks: Dict[str, np.ndarray] = {}

    @functools.lru_cache(maxsize=None)
    def observation_space(self, agent: str) -> spaces.Box:
        return _observation_space()

    @functools.lru_cache(maxsize=None)
    def action_space(self, agent: str) -> spaces.Discrete:
        return spaces.Discrete(N_ACTIONS)

    def _observe(self) -> Tuple[Dict[str, np.ndarray], Dict[str, Dict[str, Any]]]:
        ids, obs, masks = self._core.arrays()
        self.agents = list(ids)
        if self._core.scenario:
            self.possible_agents = self._core.env.possible_agents()
        observations = {a: obs[k] for k, a in enumerate(ids)}
        self._last_obs.update(observations)
        self._masks = {a: masks[k] for k, a in enumerate(ids)}
        infos = {a: {"action_mask": masks[k]} for k, a in enumerate(ids)}
        return observations, infos

    def reset(self, seed: Optional[int] = None, options: Optional[Dict[str, Any]] = None):
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        demand_seed = int(self._rng.integers(0, 2**31 - 1)) if seed is None else int(seed)
        used, _, _, _ = _reset_to_an_agent(self._core, demand_seed)
        self.possible_agents = self._core.env.possible_agents()
        self._last_obs = {}
        observations, infos = self._observe()
        for info in infos.values():
            info["demand_seed"] = used
        return observations, infos

    def step(self, actions: Dict[str, Any]):
        acting = list(self.agents)
        unknown = sorted(str(a) for a in set(actions) - set(acting))
        if unknown:
            raise ValueError(f"actions for agents that are not acting now: {', '.join(unknown)}")
        idle = self._core.env.action_names().index("idle")
        chosen = [
            _action_index(actions[a], self._masks[a], a, self.masked_actions) if a in actions else idle
            for a in acting
        ]
        rewards, terminated, truncated, _done = self._core.env.step(chosen)
        observations, infos = self._observe()
        reward = {a: 0.0 for a in acting}
        reward.update({a: float(r) for a, r in rewards})
        ended_t, ended_u = set(terminated), set(truncated)
        keys = set(acting) | set(self.agents)
        terms = {a: a in ended_t for a in keys}
        truncs = {a: a in ended_u for a in keys}
        for a in keys:
            reward.setdefault(a, 0.0)
            infos.setdefault(a, {})
            observations.setdefault(a, self._last_obs[a])
        return observations, reward, terms, truncs, infos

    def render(self):
        if self.render_mode == "rgb_array":
            return self._core.frame(*self.render_size)
        return None

    def close(self):
        self._core.env.close()


gymnasium.register(id="bkpbs/Merge-v0", entry_point="bkpbs.gym:MergeEnv")
