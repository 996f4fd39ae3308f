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
    # check_env samples actions at random, masked ones included.
    env = bg.MergeEnv(render_mode="rgb_array", steps=200, masked_actions="idle")
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

    env = bg.MergeParallelEnv(steps=150, alpha=0.6, masked_actions="idle")
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

    env = bg.MergeParallelEnv(steps=60, masked_actions="idle")
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


def _first_reset(seed: int) -> tuple:
    """The first observation, agent and demand seed of a fresh MergeEnv reset with ``seed``."""
    env = bg.MergeEnv(steps=100)
    try:
        obs, info = env.reset(seed=seed)
        return obs, info["agent"], info["demand_seed"]
    finally:
        env.close()


def test_reset_alone_decides_what_follows_whatever_ran_before():
    # Hardening II, finding 7: reset(seed=9) after an episode of seed 8 returned seed 8's agent
    # and a non-zero observation; a fresh process gave agent None, then step() said "done".
    env = bg.MergeEnv(steps=100)
    env.reset(seed=8)
    env.step(bg.MergeEnv.action_names.index("idle"))
    obs, info = env.reset(seed=9)
    after_history = (obs, info["agent"], info["demand_seed"])
    env.step(bg.MergeEnv.action_names.index("idle"))  # the episode runs
    env.close()
    fresh = _first_reset(9)
    assert after_history[1] is not None and after_history[1] == fresh[1]
    assert after_history[2] == fresh[2]
    assert np.array_equal(after_history[0], fresh[0])
    # And in another process.
    import subprocess
    import sys

    code = (
        "import bkpbs.gym as bg, numpy as np\n"
        "e = bg.MergeEnv(steps=100); o, i = e.reset(seed=9)\n"
        "print(i['agent'], i['demand_seed'], o.tobytes().hex())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    agent, seed, hexobs = out.stdout.split()
    assert (agent, int(seed), hexobs) == (fresh[1], fresh[2], fresh[0].tobytes().hex())


def test_a_seed_without_a_cav_is_skipped_and_said():
    # With 100 steps, seeds whose first CAV comes after the warm-up too late have no agent.
    seen = [_first_reset(s)[2] for s in range(8, 14)]
    assert all(used >= s for used, s in zip(seen, range(8, 14)))
    assert any(used != s for used, s in zip(seen, range(8, 14))), seen


def test_invalid_fractional_and_masked_actions_raise():
    env = bg.MergeEnv(steps=200)
    _, info = env.reset(seed=3)
    for bad in (1.5, 2.0, True, 7, -1, "left"):
        with pytest.raises(ValueError, match="action"):
            env.step(bad)
    env.step(np.int64(bg.MergeEnv.action_names.index("idle")))  # numpy integers are fine
    masked = None
    for _ in range(150):
        mask = info["action_mask"]
        if not mask.all():
            masked = int(np.flatnonzero(mask == 0)[0])
            break
        _, _, te, tr, info = env.step(bg.MergeEnv.action_names.index("idle"))
        assert not (te or tr)
    assert masked is not None, "some primitive is masked on the acceleration lane"
    with pytest.raises(ValueError, match="masked out"):
        env.step(masked)
    env.close()
    with pytest.raises(ValueError, match="masked_actions"):
        bg.MergeEnv(masked_actions="sometimes")


def test_parallel_actions_for_unknown_agents_raise():
    env = bg.MergeParallelEnv(steps=80)
    env.reset(seed=2)
    idle = bg.MergeEnv.action_names.index("idle")
    with pytest.raises(ValueError, match="not acting now: ghost"):
        env.step({**{a: idle for a in env.agents}, "ghost": idle})
    with pytest.raises(ValueError, match="not an integer"):
        env.step({a: 0.5 for a in env.agents})
    env.close()
