#!/usr/bin/env python3
"""Paired comparison of the same planners on the same cells and seeds, either of two arms of
one campaign with the predictor axis (here b_θ against the constant-speed predictor,
predictors/, `bkpbs campaign --predictors learned,constant`) or of two campaigns
(results/sumo-versions: two SUMO versions). `bkpbs report --versus bk-pbs+constant` pairs the
arms itself; this script adds the shield overrides, with the same statistics: the mean per-seed
difference with Student's 95 % interval and the two-sided Wilcoxon signed-rank p (zeros dropped;
exact below 50 pairs without ties, else normal with tie and continuity correction), as
docs/src/campaigns.md describes; beyond 31 pairs its interval takes the normal quantile 1.96
where the report takes t(0.975, n - 1), so pooled intervals differ in the second decimal.
Standard library only.

    python3 results/long-run/predictor_pairs.py results/long-run/predictors:learned \
        results/long-run/predictors:constant
    python3 results/long-run/predictor_pairs.py DIR_A DIR_B

`DIR:NAME` is the episodes of `DIR` whose predictor is NAME; a plain `DIR`, every episode of
a campaign without the predictor axis.

An optional third argument names the metrics (comma-separated; default the five below), and
per planner it then adds the controllable collisions of the two runs (vehicles removed in
collisions involving a CAV, of those inserted) with Fisher's exact two-sided p
(results/sumo-versions uses this).
"""
import csv
import math
import sys
from collections import defaultdict
from statistics import NormalDist, mean, stdev

METRICS = ["system_delay_s", "mean_delay_s", "arrived", "stranded", "shield_overrides"]
# Student t(0.975, n - 1) for n - 1 = 1..30; beyond, the normal quantile.
T975 = [12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179,
        2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
        2.060, 2.056, 2.052, 2.048, 2.045, 2.042]


def rows(directory, predictor=None):
    """The episodes of a campaign directory by cell; of a campaign with the predictor axis
    (`bkpbs campaign --predictors`), those of `predictor` only."""
    with open(f"{directory}/episodes.csv", newline="") as f:
        return {(r["planner"], r["hdv_profile"], r["alpha"], r["lambda"], r["seed"]): r
                for r in csv.DictReader(f) if r.get("predictor") == predictor}


def interval(d):
    n = len(d)
    if n < 2:
        return (math.nan, math.nan)
    t = T975[n - 2] if n - 2 < len(T975) else 1.96
    h = t * stdev(d) / math.sqrt(n)
    return (mean(d) - h, mean(d) + h)


def wilcoxon(d):
    d = [x for x in d if x != 0]
    n = len(d)
    if n == 0:
        return None, "none"
    order = sorted(range(n), key=lambda i: abs(d[i]))
    ranks = [0.0] * n
    i, ties = 0, []
    while i < n:
        j = i
        while j + 1 < n and abs(d[order[j + 1]]) == abs(d[order[i]]):
            j += 1
        for k in range(i, j + 1):
            ranks[order[k]] = (i + j) / 2 + 1
        ties.append(j - i + 1)
        i = j + 1
    v = sum(r for r, x in zip(ranks, d) if x > 0)
    if n < 50 and all(t == 1 for t in ties):
        counts = [1] + [0] * (n * (n + 1) // 2)  # ways to reach each rank sum
        for r in range(1, n + 1):
            for s in range(len(counts) - 1, r - 1, -1):
                counts[s] += counts[s - r]
        total = 2 ** n
        lo = sum(counts[: int(v) + 1]) / total
        hi = sum(counts[int(v):]) / total
        return min(1.0, 2 * min(lo, hi)), "exact"
    mu = n * (n + 1) / 4
    var = n * (n + 1) * (2 * n + 1) / 24 - sum(t ** 3 - t for t in ties) / 48
    z = (abs(v - mu) - 0.5) / math.sqrt(var)
    return min(1.0, 2 * (1 - NormalDist().cdf(z))), "normal"


def line(label, pairs):
    cells = [label, str(len(pairs))]
    for m in METRICS:
        d = [float(a[m]) - float(b[m]) for a, b in pairs if a[m] != "" and b[m] != ""]
        lo, hi = interval(d)
        p, _ = wilcoxon(d)
        p_text = "none" if p is None else ("<0.001" if p < 0.001 else f"{p:.3f}")
        cells.append(f"{mean(d):+.2f} [{lo:+.2f}, {hi:+.2f}]" if d else "")
        cells.append(p_text)
    return "| " + " | ".join(cells) + " |"


def fisher(k1, n1, k2, n2):
    """Two-sided Fisher exact p of k1 of n1 against k2 of n2 (sum of tables no likelier)."""
    k, n = k1 + k2, n1 + n2
    def prob(x):
        return math.comb(n1, x) * math.comb(n2, k - x) / math.comb(n, k)
    seen = prob(k1)
    lo, hi = max(0, k - n2), min(k, n1)
    return min(1.0, sum(prob(x) for x in range(lo, hi + 1) if prob(x) <= seen * (1 + 1e-9)))


def collisions(pairs):
    total = [[0, 0], [0, 0]]
    for a, b in pairs:
        for side, r in enumerate((a, b)):
            total[side][0] += int(r["controllable_crashed"])
            total[side][1] += int(r["inserted"])
    (k1, n1), (k2, n2) = total
    return f"controllable collisions {k1} of {n1} against {k2} of {n2}: Fisher p = {fisher(k1, n1, k2, n2):.3f}"


def main(first, second, metrics=None):
    global METRICS
    if metrics:
        METRICS = metrics.split(",")
    if ":" in first:
        # DIR:learned DIR:constant, the two arms of one campaign with the predictor axis
        (da, pa), (db, pb) = first.rsplit(":", 1), second.rsplit(":", 1)
        a, b = rows(da, pa), rows(db, pb)
    else:
        a, b = rows(first), rows(second)
    keys = sorted(set(a) & set(b))
    by_planner = defaultdict(list)
    for k in keys:
        by_planner[k[0]].append(k)
    head = "| cell | pairs | " + " | ".join(f"Δ {m} | p" for m in METRICS) + " |"
    print(f"{first} − {second}: paired on planner, HDV profile, α, λ and seed "
          f"({len(set(a) ^ set(b))} unmatched)\n")
    for planner, ks in sorted(by_planner.items()):
        print(f"### {planner}\n\n{head}\n|" + "---|" * (2 + 2 * len(METRICS)))
        cells = defaultdict(list)
        for k in ks:
            cells[k[1:4]].append(k)
        for cell, cks in sorted(cells.items()):
            print(line(" ".join(cell), [(a[k], b[k]) for k in cks]))
        print(line("**all**", [(a[k], b[k]) for k in ks]) + "\n")
        if metrics:
            print(collisions([(a[k], b[k]) for k in ks]) + "\n")


if __name__ == "__main__":
    main(*sys.argv[1:4])
