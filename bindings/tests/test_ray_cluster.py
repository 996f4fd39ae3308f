"""python -m bkpbs.campaign on a real multi-node Ray cluster on this machine whose worker nodes
cannot see the campaign's files, as between machines without shared storage: each worker node
runs in a mount namespace of its own (``unshare -m``) with a tmpfs over the tests' temporary
directory, where the campaign directory and the scenario's files are; the head node has no CPU,
so every episode runs on a worker node. The collected files must equal, byte for byte, those of
a local ``bkpbs campaign`` of the same grid.

Needs root (for the mount namespace) and ``unshare``, skipped otherwise (and with
BKPBS_CLUSTER_TESTS=0); part of ``make pytest`` (about 50 s), alone: ``make test-cluster``."""

from __future__ import annotations

import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import ramp_game
from local_cluster import ENV, Cluster

pytestmark = pytest.mark.skipif(
    os.environ.get("BKPBS_CLUSTER_TESTS") == "0"
    or os.geteuid() != 0
    or shutil.which("unshare") is None,
    reason="a Ray cluster with private mounts needs root and unshare (BKPBS_CLUSTER_TESTS=0: off)",
)

PAPER = ["--planners", "idm-mobil,sumo", "--alphas", "0.5", "--lambdas", "3000", "--seeds", "2",
         "--steps", "50"]

def campaign(cluster: Cluster, out: Path, *grid: str, check: bool = True, cwd=None):
    p = subprocess.run(
        [sys.executable, "-m", "bkpbs.campaign", "--ray", "--address", cluster.address,
         "--out", str(out), "--no-report", *grid],
        capture_output=True, text=True, timeout=600, env=ENV, cwd=cwd,
    )
    if check:
        assert p.returncode == 0, p.stdout + p.stderr
    return p


def local_campaign(cli: Path, out: Path, *grid: str, cwd=None) -> None:
    subprocess.run([str(cli), "campaign", "--out", str(out), "--workers", "2", *grid],
                   check=True, capture_output=True, cwd=cwd)


def same(a: Path, b: Path, names) -> None:
    for name in names:
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


@pytest.fixture(scope="module")
def hidden(tmp_path_factory) -> Path:
    """The directory the worker nodes cannot see: every test's temporary directory."""
    return tmp_path_factory.getbasetemp()


@pytest.fixture(scope="module")
def cluster(hidden):
    c = Cluster(hidden)
    try:
        c.add_worker(2)
        c.wait_for_cpus(2)
        yield c
    finally:
        c.stop()


def test_the_worker_node_does_not_see_the_campaign_s_files(cluster, tmp_path):
    (tmp_path / "here").write_text("only on the head's machine")
    probe = ("import os, ray; ray.init(address=%r)\n"
             "print(ray.get(ray.remote(num_cpus=1)(os.path.exists).remote(%r)))" %
             (cluster.address, str(tmp_path / "here")))
    p = subprocess.run([sys.executable, "-c", probe], env=ENV, capture_output=True, text=True,
                       timeout=120, check=True)
    assert p.stdout.strip().splitlines()[-1] == "False"


def test_a_paper_grid_travels_through_ray(cluster, tmp_path, cli):
    t0 = time.monotonic()
    out = tmp_path / "ray"
    p = campaign(cluster, out, *PAPER)
    print(f"cluster: paper grid in {time.monotonic() - t0:.1f} s")
    assert "to run: 4 on Ray" in p.stdout
    assert "4 done, 0 failed" in p.stdout and "4 episodes collected" in p.stdout, p.stdout
    local_campaign(cli, tmp_path / "local", *PAPER)
    same(out, tmp_path / "local", ["episodes.csv", "vehicles.csv", "failures.csv",
                                   "campaign.toml"])
    # Stopped and run again: the collected cells are not run again.
    assert "to run: 0" in campaign(cluster, out, *PAPER).stdout


def test_a_scenario_grid_travels_through_ray(cluster, tmp_path, cli):
    cfg = ramp_game(tmp_path / "scenario")
    grid = ["--sumocfg", str(cfg), "--planners", "bk-pbs,sumo", "--alphas", "0.5", "--seeds",
            "2", "--steps", "100"]
    t0 = time.monotonic()
    out = tmp_path / "ray"
    p = campaign(cluster, out, *grid)
    print(f"cluster: scenario grid in {time.monotonic() - t0:.1f} s")
    assert "4 done, 0 failed" in p.stdout and "4 episodes collected" in p.stdout, p.stdout
    local_campaign(cli, tmp_path / "local", *grid)
    same(out, tmp_path / "local", ["episodes.csv", "vehicles.csv", "regions.csv",
                                   "entries.csv", "failures.csv", "campaign.toml"])


def test_a_config_s_model_and_policy_files_travel_through_ray(cluster, tmp_path, cli):
    """A --config file naming a model and a policy relative to the working directory, all of
    them where the worker node cannot see them."""
    from conftest import REPO

    work = tmp_path / "work"
    shutil.copytree(REPO / "models", work / "my-models",
                    ignore=shutil.ignore_patterns("networks", "profiles"))
    (work / "grid.toml").write_text(
        '[predictor]\nconditioned_model = "my-models/gcn-conditioned.json"\n'
        'unconditioned_model = "./my-models/../my-models/gcn-unconditioned.json"\n'
        '[rl]\npolicy = "my-models/rl-ppo.json"\n'
    )
    grid = ["--config", "grid.toml", "--planners", "bk-pbs,rl-ppo", "--alphas", "0.5",
            "--lambdas", "3000", "--seeds", "1", "--steps", "50"]
    p = campaign(cluster, tmp_path / "ray", *grid, cwd=work)
    assert "2 done, 0 failed" in p.stdout, p.stdout + p.stderr
    local_campaign(cli, tmp_path / "local", *grid, cwd=work)
    same(tmp_path / "ray", tmp_path / "local", ["episodes.csv", "vehicles.csv",
                                                "failures.csv", "campaign.toml"])
    # The policy retrained in place: the cells whose settings name it run again, saying why.
    policy = work / "my-models" / "rl-ppo.json"
    policy.write_text(policy.read_text() + "\n")
    p = campaign(cluster, tmp_path / "ray", *grid, cwd=work)
    assert "rl-ppo α=0.5 λ=3000 seed=0 runs again: its rl.policy file is not the one it ran " \
        "with" in p.stdout, p.stdout
    assert "2 done, 0 failed" in p.stdout, p.stdout + p.stderr


def test_a_stopped_driver_resumes_from_the_directory(cluster, tmp_path, cli):
    """Ctrl-C after the first episodes are stored: the same command runs only the others."""
    grid = ["--planners", "idm-mobil", "--alphas", "0.5", "--lambdas", "3000", "--seeds", "6",
            "--steps", "400"]
    out = tmp_path / "ray"
    driver = subprocess.Popen(
        [sys.executable, "-m", "bkpbs.campaign", "--ray", "--address", cluster.address,
         "--out", str(out), "--no-report", *grid],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
    )
    for line in driver.stdout:
        # At least two stored and some still to come (two may finish in one wait, so the
        # progress line can skip from 1 done to 3 done).
        m = re.match(r"campaign: (\d+) done, \d+ failed, (\d+) running, (\d+) waiting", line)
        if m and int(m[1]) >= 2 and int(m[2]) + int(m[3]) > 0:
            driver.send_signal(signal.SIGINT)
            break
    _, err = driver.communicate(timeout=120)
    assert driver.returncode == 130 and "the same command resumes" in err, err
    p = campaign(cluster, out, *grid)
    left = int(p.stdout.split("to run: ")[1].split()[0])
    assert 0 < left <= 4, p.stdout
    assert f"ran {left} episodes: {left} done" in p.stdout and "6 episodes collected" in p.stdout
    local_campaign(cli, tmp_path / "local", *grid)
    same(out, tmp_path / "local", ["episodes.csv", "vehicles.csv", "failures.csv",
                                   "campaign.toml"])


def test_a_lost_node_s_episodes_run_again_elsewhere(hidden, tmp_path, cli):
    grid = ["--planners", "idm-mobil", "--alphas", "0.5", "--lambdas", "3000", "--seeds", "6",
            "--steps", "600"]
    c = Cluster(hidden)
    try:
        doomed = c.add_worker(1)
        c.add_worker(1)
        c.wait_for_cpus(2)
        out = tmp_path / "ray"
        driver = subprocess.Popen(
            [sys.executable, "-m", "bkpbs.campaign", "--ray", "--address", c.address,
             "--out", str(out), "--no-report", *grid],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV,
        )
        t0 = time.monotonic()
        # The node dies in the middle of an episode.
        while not c.running_an_episode(doomed):
            assert driver.poll() is None and time.monotonic() - t0 < 120, driver.communicate()
            time.sleep(0.02)
        c.kill(doomed)
        stdout, err = driver.communicate(timeout=600)
        print(f"cluster: a lost node's campaign in {time.monotonic() - t0:.1f} s")
        assert driver.returncode == 0, stdout + err
    finally:
        c.stop()
    assert "6 done, 0 failed" in stdout and "6 episodes collected" in stdout, stdout + err
    assert "retry 1 of 2" in err, err
    retries = (out / "retries.csv").read_text().splitlines()
    assert retries[0] == "cell,attempt,reason" and len(retries) >= 2, retries
    local_campaign(cli, tmp_path / "local", *grid)
    same(out, tmp_path / "local", ["episodes.csv", "vehicles.csv", "failures.csv",
                                   "campaign.toml"])
