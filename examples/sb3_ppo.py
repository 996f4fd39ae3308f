#!/usr/bin/env python3
"""Stable-Baselines3 PPO on the merge scenario, through bkpbs's Gymnasium environment.

Trains SB3's PPO on ``bkpbs/Merge-v0`` (one CAV among HDVs, as the paper trains its RL-PPO) with
the paper's hyper-parameters (two layers of 256, learning rate 1e-3, discount 0.95, batch 512,
10 epochs), then drives every CAV with the trained policy (shared weights, as the paper tests)
in ``bkpbs.gym.MergeParallelEnv`` on held-out seeds, and prints each episode's metrics next to
``bkpbs.run_episode`` of the core planners on the same seeds.

    .venv/bin/pip install stable-baselines3       # brings PyTorch: not part of `make test`
    .venv/bin/python examples/sb3_ppo.py --steps 200000 [--seeds 5] [--save ppo_merge.zip]

SUMO runs in-process (libsumo): one environment per process, so training uses one environment
(SB3's ``SubprocVecEnv`` would give one SUMO per subprocess).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import bkpbs
import bkpbs.gym as bg


def train(steps: int, seed: int):
    from stable_baselines3 import PPO

    # This PPO does not mask: a masked-out primitive runs as idle.
    env = bg.MergeEnv(alpha=0.5, lam=3000.0, masked_actions="idle")
    model = PPO(
        "MlpPolicy",
        env,
        learning_rate=1e-3,
        gamma=0.95,
        batch_size=512,
        n_epochs=10,
        n_steps=2048,
        policy_kwargs={"net_arch": {"pi": [256, 256], "vf": [256, 256]}},
        seed=seed,
        verbose=1,
    )
    t0 = time.time()
    model.learn(total_timesteps=steps)
    print(f"trained {steps} steps in {time.time() - t0:.0f} s")
    env.close()
    return model


def evaluate(model, alpha: float, lam: float, seeds):
    """Every CAV driven by the trained policy; the episode's summary (as episode.csv)."""
    rows = []
    for seed in seeds:
        env = bg.MergeParallelEnv(alpha=alpha, lam=lam, masked_actions="idle")
        obs, _ = env.reset(seed=seed)
        while env.agents:
            batch = np.stack([obs[a] for a in env.agents])
            actions, _ = model.predict(batch, deterministic=True)
            obs, _, _, _, _ = env.step(dict(zip(env.agents, (int(a) for a in actions))))
        rows.append(env._core.env.summary())
        env.close()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=200_000, help="training steps (default 200000)")
    ap.add_argument("--seeds", type=int, default=5, help="held-out evaluation episodes (seeds 0…)")
    ap.add_argument("--alpha", type=float, default=0.5)
    ap.add_argument("--lam", type=float, default=3000.0)
    ap.add_argument("--seed", type=int, default=1, help="training seed")
    ap.add_argument("--save", help="save the SB3 model here")
    args = ap.parse_args()

    model = train(args.steps, args.seed)
    if args.save:
        model.save(args.save)
    seeds = list(range(args.seeds))
    table = {"sb3-ppo": evaluate(model, args.alpha, args.lam, seeds)}
    for planner in ["idm-mobil", "rl-ppo", "bk-pbs"]:
        table[planner] = [bkpbs.run_episode(planner, args.alpha, args.lam, s) for s in seeds]
    print(f"\nα = {args.alpha}, λ = {args.lam}, seeds {seeds[0]}–{seeds[-1]}")
    print(f"{'planner':10} {'delay (s)':>10} {'controllable collision rate':>28}")
    for name, rows in table.items():
        delay = np.nanmean([np.nan if r["mean_delay_s"] is None else r["mean_delay_s"] for r in rows])
        rate = np.mean([r["controllable_collision_rate"] for r in rows])
        print(f"{name:10} {delay:10.2f} {100 * rate:27.2f}%")


if __name__ == "__main__":
    main()
