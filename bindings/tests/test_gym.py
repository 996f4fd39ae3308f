"""The Gymnasium and PettingZoo environments on real SUMO, checked by the libraries' own tests."""

from __future__ import annotations

import gymnasium
import numpy as np
import pytest

import bkpbs.gym as bg
from bkpbs import BkpbsError


def test_merge_env_passes_gymnasium_check_env():
    from gymnasium.utils.env_checker import check_env

    # An instance, not gymnasium.make's: with a spec, check_env opens a second environment for
    # the other render modes while the first is open, and libsumo has one simulation per process.
    env = bg.MergeEnv(render_mode="rgb_array", steps=200)
    try:
        check_env(env, skip_render_check=False)
    finally:
        env.close()


def test_registered_and_an_episode_runs_to_its_end():
    env = gymnasium.make("bkpbs/Merge-v0", steps=250)
    obs, info = env.reset(seed=3)
    assert obs.shape == (bg.OBS_DIM,) and obs.dtype == np.float32
    assert info["action_mask"].shape == (6,)
    idle = bg.MergeEnv.action_names.index("idle")
    total, steps, ended = 0.0, 0, False
    while not ended:
        obs, r, terminated, truncated, info = env.step(idle)
        total += r
        steps += 1
        ended = terminated or truncated
    assert steps > 10 and np.isfinite(total)
    assert info["episode_summary"] is None or "inserted" in info["episode_summary"]
    frame = env.unwrapped.render()
    assert frame is None  # no render mode asked for
    env.close()


def test_same_seed_same_episode():
    env = bg.MergeEnv(steps=200)
    runs = []
    for _ in range(2):
        obs, _ = env.reset(seed=7)
        seq = [obs]
        for a in [0, 0, 1, 2, 1, 0, 1, 1]:
            obs, r, te, tr, _ = env.step(a)
            seq.append(obs)
            if te or tr:
                break
        runs.append(np.stack(seq))
    env.close()
    assert np.array_equal(runs[0], runs[1])


def test_merge_parallel_env_passes_pettingzoo_parallel_api_test():
    from pettingzoo.test import parallel_api_test

    env = bg.MergeParallelEnv(steps=150, alpha=0.6)
    try:
        parallel_api_test(env, num_cycles=200)
    finally:
        env.close()


def test_render_and_bad_input():
    env = bg.MergeParallelEnv(render_mode="rgb_array", steps=100)
    obs, infos = env.reset(seed=1)
    frame = env.render()
    assert frame.shape == (150, 600, 3) and frame.dtype == np.uint8
    # CAV agents are drawn red: at least one red pixel once an agent exists.
    if env.agents:
        red = (frame[:, :, 0] > 200) & (frame[:, :, 1] < 80)
        assert red.any()
    env.close()
    with pytest.raises(BkpbsError, match="agents"):
        bg.MergeEnvCore("some", 0.5, 3000.0, None)
    with pytest.raises(BkpbsError):
        bg.MergeEnv(steps=-1)


def test_misuse_is_one_clear_error():
    from bkpbs import SimulationBusyError

    env = bg.MergeParallelEnv(steps=60)
    env.reset(seed=2)
    n = len(env.agents)
    with pytest.raises(BkpbsError, match="not one of the 6 primitives"):
        env._core.env.step([9] * n)
    with pytest.raises(BkpbsError, match=f"expected {n} actions"):
        env._core.env.step([])
    other = bg.MergeEnv(steps=60)
    with pytest.raises(SimulationBusyError):
        other.reset(seed=1)  # libsumo: one simulation per process
    while env.agents:
        env.step({a: 1 for a in env.agents})
    with pytest.raises(BkpbsError, match="done"):
        env._core.env.step([])
    env.close()
    other.reset(seed=1)  # free again
    other.close()
