#!/usr/bin/env python3
"""The learned-per-scenario study's paired tables (pairs.md): arms of the campaigns in this
directory paired on scenario, α, seed and region. Per pair of arms: the region's mean system
delay (regions.csv `mean_delay_s`) and the vehicles never inserted (episodes.csv), each as the
mean per-seed difference with Student's 95 % interval and the two-sided Wilcoxon signed-rank p;
and the vehicles removed in controllable collisions (of those inserted) with Fisher's exact
two-sided p. The statistics are results/long-run/predictor_pairs.py's. Standard library only.

    python3 results/learned-per-scenario/pairs.py results/learned-per-scenario > pairs.md
"""
import csv
import os
import sys
from statistics import mean

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "long-run"))
from predictor_pairs import fisher, interval, wilcoxon  # noqa: E402

# Each arm: its label, its campaign directory, planner and predictor arm (None: no axis).
ARMS = {
    "bk-pbs, ramp-trained b_θ": ("ramp-trained", "bk-pbs", None),
    "bk-pbs, paper b_θ": ("paper-trained", "bk-pbs", "learned"),
    "bk-pbs, constant speed": ("paper-trained", "bk-pbs", "constant"),
    "sumo": ("baselines", "sumo", None),
    "rl-ppo, paper policy, shield off": ("baselines", "rl-ppo", None),
    "rl-ppo, ramp-trained policy, shield off": ("ramp-trained", "rl-ppo", None),
    "rl-ppo, paper policy, shield on": ("rl-shield-on/paper", "rl-ppo", None),
    "rl-ppo, ramp-trained policy, shield on": ("rl-shield-on/ramp-trained", "rl-ppo", None),
}

PAIRS = [
    ("bk-pbs, ramp-trained b_θ", "bk-pbs, constant speed"),
    ("bk-pbs, ramp-trained b_θ", "bk-pbs, paper b_θ"),
    ("bk-pbs, paper b_θ", "bk-pbs, constant speed"),
    ("bk-pbs, ramp-trained b_θ", "sumo"),
    ("bk-pbs, paper b_θ", "sumo"),
    ("bk-pbs, constant speed", "sumo"),
    ("rl-ppo, ramp-trained policy, shield off", "rl-ppo, paper policy, shield off"),
    ("rl-ppo, ramp-trained policy, shield on", "rl-ppo, paper policy, shield on"),
]


def read(root, directory, name, planner, predictor, key):
    with open(os.path.join(root, directory, name), newline="") as f:
        return {key(r): r for r in csv.DictReader(f)
                if r["planner"] == planner and r.get("predictor") == predictor}


def arm(root, label):
    directory, planner, predictor = ARMS[label]
    regions = read(root, directory, "regions.csv", planner, predictor,
                   lambda r: (r["scenario"], r["alpha"], r["seed"], r["region"]))
    episodes = read(root, directory, "episodes.csv", planner, predictor,
                    lambda r: (r["scenario"], r["alpha"], r["seed"]))
    return regions, episodes


def p_text(p):
    return "none" if p is None else ("<0.001" if p < 0.001 else f"{p:.3f}")


def stat(d):
    lo, hi = interval(d)
    p, _ = wilcoxon(d)
    return f"{mean(d):+.2f} [{lo:+.2f}, {hi:+.2f}] | {p_text(p)}"


def collisions(rows):
    k = sum(int(r["controllable_crashed"]) for r in rows)
    n = sum(int(r["inserted"]) for r in rows)
    hit = sum(1 for r in rows if int(r["controllable_crashed"]) > 0)
    return k, n, hit


def main(root):
    arms = {label: arm(root, label) for label in ARMS}
    print("Pairs of arms (A − B) on scenario, α, seed and region; delay: the region's mean system "
          "delay (s); never inserted: per episode; controllable collisions: vehicles of those "
          "inserted, episodes with any in brackets, Fisher's exact p.\n")
    print("| A | B | pairs | Δ delay [95 %] | p | Δ never inserted [95 %] | p "
          "| collisions A | collisions B | Fisher p |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for a, b in PAIRS:
        (ra, ea), (rb, eb) = arms[a], arms[b]
        keys = sorted(set(ra) & set(rb))
        ekeys = sorted(set(ea) & set(eb))
        delay = [float(ra[k]["mean_delay_s"]) - float(rb[k]["mean_delay_s"]) for k in keys]
        never = [int(ea[k]["never_inserted"]) - int(eb[k]["never_inserted"]) for k in ekeys]
        (k1, n1, h1), (k2, n2, h2) = (collisions([e[k] for k in ekeys]) for e in (ea, eb))
        print(f"| {a} | {b} | {len(keys)} | {stat(delay)} | {stat(never)} "
              f"| {k1} of {n1} ({h1}) | {k2} of {n2} ({h2}) | {p_text(fisher(k1, n1, k2, n2))} |")
    print("\nPer arm: mean over its episodes.\n")
    print("| arm | episodes | region delay (s) | never inserted | controllable collisions "
          "| per episode |")
    print("|---|---|---|---|---|---|")
    for label, (r, e) in arms.items():
        k, n, h = collisions(list(e.values()))
        d = mean(float(x["mean_delay_s"]) for x in r.values())
        ni = mean(int(x["never_inserted"]) for x in e.values())
        print(f"| {label} | {len(e)} | {d:.2f} | {ni:.1f} | {k} of {n} ({h} episodes) "
              f"| {k / len(e):.1f} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__)))
