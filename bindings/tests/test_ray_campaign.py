"""python -m bkpbs.campaign: four tiny episodes on a local Ray (and two in local processes),
into the layout of `bkpbs campaign`, byte for byte, which `bkpbs report` reads."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import bkpbs
from conftest import ramp_game

GRID = ["--planners", "idm-mobil,sumo", "--alphas", "0.5", "--lambdas", "3000", "--seeds", "2",
        "--steps", "25"]


def campaign(*args, check=True):
    p = subprocess.run(
        [sys.executable, "-m", "bkpbs.campaign", *args], capture_output=True, text=True,
        timeout=600,
    )
    if check:
        assert p.returncode == 0, p.stdout + p.stderr
    return p


@pytest.fixture(scope="module")
def rust_campaign(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("rust")
    subprocess.run([str(cli), "campaign", "--out", str(out), "--workers", "2", *GRID],
                   check=True, capture_output=True)
    return out


def same_results(a, b):
    for name in ("episodes.csv", "vehicles.csv", "failures.csv", "campaign.toml"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_ray_campaign_matches_the_rust_campaign(tmp_path, rust_campaign, cli):
    out = tmp_path / "ray"
    p = campaign("--ray", "--num-cpus", "2", "--out", str(out), *GRID)
    assert "to run: 4 on Ray" in p.stdout and "4 episodes collected" in p.stdout
    rows = (out / "episodes.csv").read_text().splitlines()
    assert len(rows) == 5
    # Grid order: planner as listed, then seed.
    assert [r.split(",")[0] + "/" + r.split(",")[3] for r in rows[1:]] == [
        "idm-mobil/0", "idm-mobil/1", "sumo/0", "sumo/1"]
    for planner in ("idm-mobil", "sumo"):
        for seed in (0, 1):
            assert (out / "episodes" / planner / f"a0.5_l3000_s{seed}" / "episode.csv").is_file()
    assert len((out / "timings.csv").read_text().splitlines()) == 5
    same_results(out, rust_campaign)
    r = subprocess.run([str(cli), "report", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "Controllable collision rate" in r.stdout
    # Resuming finds everything done.
    p = campaign("--ray", "--num-cpus", "2", "--out", str(out), "--no-report", *GRID)
    assert "to run: 0" in p.stdout


def test_local_processes_give_the_same_directory(tmp_path, rust_campaign):
    out = tmp_path / "local"
    campaign("--workers", "2", "--out", str(out), "--no-report", *GRID)
    same_results(out, rust_campaign)


def test_bad_grid_is_refused(tmp_path):
    p = campaign("--out", str(tmp_path / "x"), "--alphas", "1.5", check=False)
    assert p.returncode == 1 and "α 1.5 must lie in [0, 1]" in p.stderr
    with pytest.raises(bkpbs.BkpbsError, match="unknown planner"):
        bkpbs.Campaign(tmp_path / "y", planners=["idm-mobil", "nope"])


def test_campaign_cells_and_tasks(tmp_path):
    c = bkpbs.Campaign(tmp_path, planners=["sumo"], alphas=[0.4, 0.8], lambdas=[2500], seeds=2, steps=10)
    cells = c.cells()
    assert c.grid_size == len(cells) == 4
    assert [(x["alpha"], x["seed"]) for x in cells] == [(0.4, 0), (0.4, 1), (0.8, 0), (0.8, 1)]
    tasks = c.prepare()
    assert [t.position for t in tasks] == [0, 1, 2, 3]
    import pickle

    t = pickle.loads(pickle.dumps(tasks[1]))
    assert (t.planner, t.alpha, t.lam, t.seed) == ("sumo", 0.4, 2500.0, 1)
    assert t.run() is None
    summary = c.collect()
    assert summary["collected"] == 1 and summary["failed"] == 3
    assert len(c.prepare()) == 3


def test_a_ray_campaign_over_a_scenario_of_your_own_matches_the_rust_one(tmp_path, cli):
    cfg = ramp_game(tmp_path)
    grid = ["--sumocfg", str(cfg), "--planners", "bk-pbs,sumo", "--alphas", "0.5", "--seeds", "2",
            "--steps", "100"]
    rust = tmp_path / "rust"
    subprocess.run([str(cli), "campaign", "--out", str(rust), "--workers", "2", *grid],
                   check=True, capture_output=True)
    out = tmp_path / "ray"
    p = campaign("--ray", "--num-cpus", "2", "--out", str(out), *grid)
    assert "to run: 4 on Ray" in p.stdout and "4 episodes collected" in p.stdout
    for name in ("episodes.csv", "regions.csv", "entries.csv", "vehicles.csv", "failures.csv",
                 "campaign.toml"):
        assert (out / name).read_bytes() == (rust / name).read_bytes(), name
    assert (out / "report" / "paired_regions.csv").is_file()
    c = bkpbs.Campaign(out, sumocfg=[cfg], planners="bk-pbs,sumo", alphas=[0.5], seeds=2,
                       steps=100)
    assert [(x["planner"], x["scenario"], x["seed"]) for x in c.cells()][-1] == ("sumo", cfg, 1)
    assert c.prepare() == []
    # A narrower grid would drop collected episodes from episodes.csv: refused.
    with pytest.raises(bkpbs.BkpbsError, match="outside this grid"):
        bkpbs.Campaign(out, sumocfg=[cfg], planners="sumo", alphas=[0.5], seeds=2,
                       steps=100).prepare()


def test_failed_and_lost_episodes_on_ray_are_told_apart(tmp_path):
    """A planner panic (seed 0) fails once and is not retried; a worker process that dies
    (seed 1, as a SUMO abort would) runs again up to --max-retries, recorded in retries.csv,
    then fails. The last lines agree with each other and with failures.csv."""
    import os
    import tempfile

    # A task's directory whose process is gone (a worker that died) is swept by later tasks.
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    stale = Path(tempfile.gettempdir()) / f"bkpbs-task-{gone}-test"
    (stale / "inputs").mkdir(parents=True)
    out = tmp_path / "faults"
    grid = ["--planners", "sumo", "--alphas", "0.5", "--lambdas", "3000", "--seeds", "3",
            "--steps", "10"]
    results = {}
    for fault, seed in (("panic", 0), ("exit", 1)):
        env = dict(os.environ, BKPBS_WORKER_FAULT=f"{fault}:{seed}")
        results[fault] = subprocess.run(
            [sys.executable, "-m", "bkpbs.campaign", "--ray", "--num-cpus", "2", "--max-retries",
             "1", "--out", str(out / fault), "--no-report", *grid],
            capture_output=True, text=True, timeout=600, env=env,
        )
    panic, lost = results["panic"], results["exit"]
    assert panic.returncode == 1 and "ran 3 episodes: 2 done, 1 failed" in panic.stdout
    assert "error: 1 episodes failed" in panic.stderr and "retry" not in panic.stderr
    assert "injected planner fault" in (out / "panic" / "failures.csv").read_text()
    assert not (out / "panic" / "retries.csv").exists()
    assert lost.returncode == 1 and "ran 3 episodes: 2 done, 1 failed" in lost.stdout, lost.stdout
    assert "retry 1 of 1" in lost.stderr and "error: 1 episodes failed" in lost.stderr
    retries = (out / "exit" / "retries.csv").read_text().splitlines()
    assert retries[0] == "cell,attempt,reason" and len(retries) == 2, retries
    assert retries[1].startswith("episodes/sumo/a0.5_l3000_s1,1,")
    assert "lost 2 times" in (out / "exit" / "failures.csv").read_text()
    assert not stale.exists()
