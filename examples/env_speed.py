#!/usr/bin/env python3
"""Environment steps per second of bkpbs's Python environments, to set beside ``bkpbs train-rl``.

Runs whole episodes of ``MergeParallelEnv`` (every CAV an agent; one environment step = one CAV
decision, as the Rust trainer counts them) and of ``MergeEnv`` (one agent), choosing uniformly
among the allowed primitives, and prints the decisions per second of wall time (one process, so
one SUMO).

    .venv/bin/python examples/env_speed.py [--episodes 8]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import bkpbs.gym as bg


def parallel(episodes: int, rng: np.random.Generator) -> float:
    env = bg.MergeParallelEnv(alpha=0.6, lam=3000.0)
    steps, t0 = 0, time.perf_counter()
    for seed in range(episodes):
        obs, infos = env.reset(seed=seed)
        while env.agents:
            acts = {a: int(rng.choice(np.flatnonzero(infos[a]["action_mask"]))) for a in env.agents}
            steps += len(acts)
            obs, _, _, _, infos = env.step(acts)
    env.close()
    return steps / (time.perf_counter() - t0)


def single(episodes: int, rng: np.random.Generator) -> float:
    env = bg.MergeEnv(alpha=0.6, lam=3000.0)
    steps, t0 = 0, time.perf_counter()
    for seed in range(episodes):
        _, info = env.reset(seed=seed)
        done = False
        while not done:
            _, _, te, tr, info = env.step(int(rng.choice(np.flatnonzero(info["action_mask"]))))
            steps += 1
            done = te or tr
    env.close()
    return steps / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--episodes", type=int, default=8)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print(f"MergeParallelEnv: {parallel(args.episodes, rng):.0f} CAV decisions/s")
    print(f"MergeEnv:         {single(args.episodes, rng):.0f} decisions/s (one agent per SUMO step)")


if __name__ == "__main__":
    main()
