"""A Ray cluster on this machine whose worker nodes cannot see the campaign's files, as between
machines without shared storage: a head node without CPUs, and worker nodes each in a mount
namespace of its own (``unshare -m``) with a tmpfs over ``hidden``. Needs root and ``unshare``.
Used by ``test_ray_cluster.py`` and ``bench_cluster.py``."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import List

# A private cluster: no token shared with other clusters of this machine, no usage report;
# a lost node noticed within a few seconds.
ENV = dict(os.environ, RAY_AUTH_MODE="disabled", RAY_USAGE_STATS_ENABLED="0",
           RAY_health_check_period_ms="1000", RAY_health_check_failure_threshold="3")
RAY = [sys.executable, "-m", "ray.scripts.scripts", "start", "--block", "--disable-usage-stats"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Cluster:
    """A head node without CPUs and worker nodes that do not see ``hidden``; every process is
    ended by its process group, and any left (found by the cluster's own temporary directory)
    by its id."""

    def __init__(self, hidden: Path):
        self.hidden = hidden
        # Short: Ray's sockets live below it.
        self.temp = tempfile.mkdtemp(prefix="bkr-", dir="/tmp")
        self.address = f"127.0.0.1:{free_port()}"
        self.nodes: List[subprocess.Popen] = []
        head = RAY + ["--head", "--num-cpus", "0", "--port", self.address.split(":")[1],
                      "--node-ip-address", "127.0.0.1", "--temp-dir", self.temp,
                      "--include-dashboard", "false",
                      "--dashboard-agent-listen-port", str(free_port())]
        self.head = self._start(head, "head")

    def _start(self, command: List[str], name: str) -> subprocess.Popen:
        log = open(os.path.join(self.temp, f"{name}.log"), "w")
        p = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT, env=ENV,
                             start_new_session=True)
        deadline = time.monotonic() + 120
        while "Ray runtime started" not in Path(log.name).read_text():
            assert p.poll() is None and time.monotonic() < deadline, Path(log.name).read_text()
            time.sleep(0.5)
        return p

    def add_worker(self, cpus: int) -> subprocess.Popen:
        start = " ".join(RAY + ["--address", self.address, "--num-cpus", str(cpus),
                                "--node-ip-address", "127.0.0.1",
                                "--dashboard-agent-listen-port", str(free_port())])
        hide = f"mount -t tmpfs bkpbs-hidden {self.hidden} && exec {start}"
        p = self._start(["unshare", "-m", "--propagation", "private", "sh", "-c", hide],
                        f"worker{len(self.nodes)}")
        self.nodes.append(p)
        return p

    def wait_for_cpus(self, cpus: int) -> None:
        probe = ("import ray, time; ray.init(address=%r)\n"
                 "while ray.cluster_resources().get('CPU', 0) < %d: time.sleep(0.5)" %
                 (self.address, cpus))
        subprocess.run([sys.executable, "-c", probe], env=ENV, check=True, timeout=120,
                       capture_output=True)

    @staticmethod
    def processes(p: subprocess.Popen) -> List[int]:
        """The processes of the worker node `p` started: those in its mount namespace."""
        try:
            ns = os.readlink(f"/proc/{p.pid}/ns/mnt")
        except OSError:
            return []
        if ns == os.readlink("/proc/self/ns/mnt"):
            return []
        pids = []
        for pid in filter(str.isdigit, os.listdir("/proc")):
            try:
                if os.readlink(f"/proc/{pid}/ns/mnt") == ns:
                    pids.append(int(pid))
            except OSError:
                pass
        return pids

    def running_an_episode(self, p: subprocess.Popen) -> bool:
        """Is a Ray task of the campaign running on the worker node `p` (a worker process
        titled after the task's function)?"""
        for pid in self.processes(p):
            try:
                if Path(f"/proc/{pid}/cmdline").read_bytes().startswith(b"ray::_run_remote"):
                    return True
            except OSError:
                pass
        return False

    def kill(self, p: subprocess.Popen) -> None:
        """Ends the node at once, as a machine that fails: `ray start` and its process group,
        and for a worker node every process in its mount namespace (Ray's worker processes
        have process groups of their own)."""
        pids = self.processes(p)
        try:
            os.killpg(p.pid, signal.SIGKILL)  # `ray start --block` ignores SIGTERM
        except ProcessLookupError:
            pass
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        p.wait()

    def stop(self) -> None:
        for p in self.nodes + [self.head]:
            self.kill(p)
        for pid in os.listdir("/proc"):
            try:
                cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
            except OSError:
                continue
            if pid.isdigit() and self.temp.encode() in cmdline:
                try:
                    os.kill(int(pid), signal.SIGKILL)
                except ProcessLookupError:
                    pass
        shutil.rmtree(self.temp, ignore_errors=True)
