"""The summary dict holds the values `episode.csv` is written from: typed, at full precision.

The CSV rounds its floats (delays and mean speed to 4 decimals, throughput to 2, the collision
rate to 6); the dict must not: its floats are the f64 values themselves, so formatting them the
CSV's way gives the CSV's text, and the rates equal their defining quotients exactly.
"""

from __future__ import annotations

import csv

import bkpbs
from conftest import csv_text

DT = 0.2


def test_dict_is_the_csv_row_at_full_precision(tmp_path):
    summary = bkpbs.run_episode("idm-mobil", 0.6, 3000, 3, steps=150, out=tmp_path)
    with open(tmp_path / "episode.csv", newline="") as f:
        (row,) = list(csv.DictReader(f))
    assert list(summary) == list(row)

    for k, text in row.items():
        got = summary[k]
        assert got is None or isinstance(got, (str, int, float)), k
        if text != "" and text.lstrip("-").isdigit():
            # An integral α or λ is a float written without decimals; counts are ints.
            assert isinstance(got, float) if k in ("alpha", "lambda") else type(got) is int, k
        assert csv_text(got, text) == text, k

    # Not the CSV text parsed back: the floats keep digits the CSV rounds away.
    rounded = {k for k, text in row.items() if isinstance(summary[k], float) and summary[k] != float(text)}
    assert {"mean_speed_mps", "mean_delay_s"} <= rounded, rounded

    # The exact f64 the core computed, bit for bit.
    assert summary["arrived"] > 0 and summary["inserted"] > 0
    # Throughput is per hour of the window in which arrivals were possible.
    assert 0 < summary["throughput_window_s"] <= (summary["steps"] - 1) * DT
    assert summary["throughput_veh_h"] == summary["arrived"] / (summary["throughput_window_s"] / 3600.0)
    assert summary["controllable_collision_rate"] == summary["controllable_crashed"] / summary["inserted"]
    assert summary["alpha"] == 0.6 and summary["lambda"] == 3000.0

    # The mean delay is the mean of the vehicles' delays, which vehicles.csv rounds each to 4
    # decimals: the two agree to within that rounding, and the dict's mean is the finer one.
    with open(tmp_path / "vehicles.csv", newline="") as f:
        delays = [float(r["delay_s"]) for r in csv.DictReader(f) if r["delay_s"] != ""]
    assert abs(sum(delays) / len(delays) - summary["mean_delay_s"]) <= 5e-5 + 1e-12
    # So is the system delay, over every vehicle with one (arrived, present, never inserted).
    with open(tmp_path / "vehicles.csv", newline="") as f:
        system = [float(r["system_delay_s"]) for r in csv.DictReader(f) if r["system_delay_s"] != ""]
    assert abs(sum(system) / len(system) - summary["system_delay_s"]) <= 5e-5 + 1e-12
