"""The Gymnasium and PettingZoo environments on a SUMO scenario of the user's own (SUMO's shipped
``ramp`` game, ``sumocfg=``), checked by the libraries' own tests: every merge region's CAVs are
the agents, and the single agent is the scenario's one CAV."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import bkpbs.gym as bg
from bkpbs import BkpbsError
from conftest import ramp_game


def test_merge_env_on_a_scenario_passes_gymnasium_check_env(tmp_path: Path) -> None:
    from gymnasium.utils.env_checker import check_env

    env = bg.MergeEnv(sumocfg=ramp_game(tmp_path), render_mode="rgb_array", steps=200,
                      masked_actions="idle")
    try:
        check_env(env, skip_render_check=False)
    finally:
        env.close()


def test_one_agent_among_the_scenarios_vehicles(tmp_path: Path) -> None:
    env = bg.MergeEnv(sumocfg=ramp_game(tmp_path), alpha=0.5, steps=300)
    obs, info = env.reset(seed=4)
    ego = info["agent"]
    assert obs.shape == (bg.OBS_DIM,) and np.isfinite(obs).all()
    idle = bg.MergeEnv.action_names.index("idle")
    steps, ended, total = 0, False, 0.0
    while not ended:
        obs, r, terminated, truncated, info = env.step(idle)
        total += r
        steps += 1
        ended = terminated or truncated
        assert info["agent"] == ego
    assert steps > 20 and np.isfinite(total)
    assert env._core.env.possible_agents() == [ego]
    env.close()
    row = env._core.env.summary()
    assert row["planner"] == "rl-env" and row["scenario"] == "ramp.sumocfg"
    assert row["inserted_cav"] == 1 and row["inserted"] > 40


def test_merge_parallel_env_on_a_scenario_passes_pettingzoo_parallel_api_test(tmp_path: Path) -> None:
    from pettingzoo.test import parallel_api_test

    env = bg.MergeParallelEnv(sumocfg=ramp_game(tmp_path), steps=150, alpha=0.6,
                              masked_actions="idle")
    try:
        parallel_api_test(env, num_cycles=200)
        env.reset(seed=5)
        assert env.agents and set(env.agents) <= set(env.possible_agents)
    finally:
        env.close()


def test_a_demand_rate_with_a_scenario_is_refused(tmp_path: Path) -> None:
    with pytest.raises(BkpbsError, match="lam = 3000.*its own demand"):
        bg.MergeEnv(sumocfg=ramp_game(tmp_path), lam=3000.0)
