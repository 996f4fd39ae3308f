"""The Ray runner of ``python -m bkpbs.campaign --ray``: one Ray task per episode, on any node of
a cluster, sharing no files with the machine the campaign runs on.

Inputs travel through Ray: the files an episode reads (:meth:`CampaignTask.inputs`: its
``.sumocfg`` and every file that names, model, calibration and policy files) are read here, put
into Ray's object store once per content (addressed by SHA-256) and handed to the task, which
writes them into a private temporary directory on its node and runs the episode against them
(:meth:`CampaignTask.run_portable`). Results travel back the same way: the task returns the
cell's files as bytes and they are written into the campaign directory here
(:meth:`CampaignTask.store`), so a cell is finished only once its files are on this machine. A
node needs SUMO and the ``bkpbs`` wheel, nothing at any path of the campaign's.

A task whose worker process or node is lost is submitted again, up to ``max_retries`` times;
each retry is printed and recorded in ``<out>/retries.csv``. An episode that fails (a SUMO
error, a planner panic) is not retried: its ``error.txt`` says why, as in a local run.
"""

from __future__ import annotations

import csv
import hashlib
import os
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections import deque
from typing import Any, Deque, Dict, List, Optional, Sequence, Tuple

from ._bkpbs import BkpbsError, CampaignTask

#: A failed task and its error message.
Failure = Tuple[CampaignTask, str]

#: The file in the campaign directory that records every retried task.
RETRIES_FILE = "retries.csv"


#: The private directories of the tasks: ``bkpbs-task-<pid>-<random>`` in the node's temporary
#: directory.
SCRATCH_PREFIX = "bkpbs-task-"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return True


def _sweep_stale_scratch(tmp: str) -> None:
    """Removes the private directories of tasks whose process is gone (killed with its node,
    or by a SUMO abort), which could not remove their own."""
    for name in os.listdir(tmp):
        pid = name[len(SCRATCH_PREFIX):].split("-", 1)[0]
        if name.startswith(SCRATCH_PREFIX) and pid.isdigit() and not _alive(int(pid)):
            shutil.rmtree(os.path.join(tmp, name), ignore_errors=True)


def _run_remote(task: CampaignTask, base: str, inputs: List[Tuple[str, Any]]):
    """The Ray task: fetches the inputs, runs the episode in a private directory, returns
    ``(error, files)`` (see :meth:`CampaignTask.run_portable`)."""
    import ray

    data = ray.get([ref for _, ref in inputs])
    _sweep_stale_scratch(tempfile.gettempdir())
    scratch = tempfile.mkdtemp(prefix=f"{SCRATCH_PREFIX}{os.getpid()}-")
    try:
        return task.run_portable(scratch, base, [(p, b) for (p, _), b in zip(inputs, data)])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def describe(task: CampaignTask) -> str:
    """The episode as the status lines name it."""
    if task.scenario is not None:
        return f"{task.planner} {task.scenario} α={task.alpha} seed={task.seed}"
    return f"{task.planner} α={task.alpha} λ={task.lam} seed={task.seed}"


class _Inputs:
    """The tasks' input files, each read once and put into the object store once per content."""

    def __init__(self, ray: Any, base: str):
        self._ray, self._base = ray, base
        self._digest_of: Dict[str, str] = {}
        self._ref_of: Dict[str, Any] = {}

    def of(self, task: CampaignTask) -> List[Tuple[str, Any]]:
        refs = []
        for path in map(str, task.inputs(self._base)):
            if path not in self._digest_of:
                with open(path, "rb") as f:
                    data = f.read()
                digest = hashlib.sha256(data).hexdigest()
                if digest not in self._ref_of:
                    self._ref_of[digest] = self._ray.put(data)
                self._digest_of[path] = digest
            refs.append((path, self._ref_of[self._digest_of[path]]))
        return refs


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"


class _Stop:
    """Ctrl-C while the run waits: noted here and acted on between two short waits, as a
    ``KeyboardInterrupt`` raised inside one of Ray's own calls can be lost there (the driver
    then ran every remaining episode and exited 0, seen with Ray 2.x)."""

    def __init__(self) -> None:
        self.requested = False

    def __call__(self, signum: int, frame: Any) -> None:
        self.requested = True


class _Run:
    """One pass over the tasks: submission bounded by the cluster's CPUs, results stored as they
    come, lost tasks retried, a progress line per finished episode."""

    def __init__(self, ray: Any, tasks: Sequence[CampaignTask], out: Optional[str],
                 max_retries: int, stop: Optional[_Stop] = None):
        self.ray, self.out, self.max_retries = ray, out, max_retries
        self.stop = stop
        self.remote = ray.remote(max_calls=1, num_cpus=1, max_retries=0)(_run_remote)
        self.base = os.getcwd()
        self.inputs = _Inputs(ray, self.base)
        self.waiting: Deque[CampaignTask] = deque(tasks)
        self.running: Dict[Any, CampaignTask] = {}
        self.attempts: Dict[int, int] = {}
        self.done = 0
        self.failures: List[Failure] = []
        self.start = time.monotonic()

    def run(self) -> List[Failure]:
        finished = False
        while self.waiting or self.running:
            self._submit()
            if finished:
                self._progress()
            ready = self._next_finished()
            task = self.running.pop(ready[0])
            finished = self._finish(task, ready[0])
        if finished:
            self._progress()
        return self.failures

    def _next_finished(self) -> List[Any]:
        """Waits for the next finished task; a Ctrl-C noted meanwhile stops the run."""
        while True:
            if self.stop is not None and self.stop.requested:
                raise KeyboardInterrupt
            timeout = None if self.stop is None else 0.5
            ready, _ = self.ray.wait(list(self.running), num_returns=1, timeout=timeout)
            if ready:
                return ready

    def _submit(self) -> None:
        """Submits waiting tasks while the cluster has a CPU for each (so "running" means it)."""
        slots = max(1, int(self.ray.cluster_resources().get("CPU", 0)))
        while self.waiting and len(self.running) < slots:
            task = self.waiting.popleft()
            try:
                inputs = self.inputs.of(task)
            except OSError as e:
                self._fail(task, f"cannot read its input: {e}")
                continue
            self.running[self.remote.remote(task, self.base, inputs)] = task

    def _finish(self, task: CampaignTask, ref: Any) -> bool:
        """Stores or records the task's outcome; False when it is submitted again."""
        from ray.exceptions import RayError, RayTaskError

        try:
            error, files = self.ray.get(ref)
        except RayError as e:
            cause = e.cause if isinstance(e, RayTaskError) else e
            if isinstance(e, RayTaskError) and not isinstance(cause, RayError):
                error = f"the episode's task raised {type(cause).__name__}: {cause}"
            elif self._retry(task, e):
                return False
            else:
                error = (f"worker process or node lost {self.max_retries + 1} times, last: "
                         f"{type(e).__name__}: {_first_line(e)}")
        if error is None:
            try:
                task.store(files)
            except (OSError, BkpbsError) as e:
                error = f"the episode ran but its files could not be stored here: {e}"
        if error is None:
            self.done += 1
        else:
            self._fail(task, error)
        return True

    def _fail(self, task: CampaignTask, error: str) -> None:
        task.record_failure(error)
        print(f"campaign: episode {describe(task)} failed: {error}", file=sys.stderr)
        self.failures.append((task, error))

    def _retry(self, task: CampaignTask, e: Exception) -> bool:
        attempt = self.attempts.get(task.position, 0) + 1
        if attempt > self.max_retries:
            return False
        self.attempts[task.position] = attempt
        why = f"{type(e).__name__}: {_first_line(e)}"
        print(f"campaign: episode {describe(task)} lost its worker ({why}); "
              f"retry {attempt} of {self.max_retries}", file=sys.stderr, flush=True)
        if self.out is not None:
            _record_retry(self.out, task, attempt, why)
        self.waiting.appendleft(task)
        return True

    def _progress(self) -> None:
        finished = self.done + len(self.failures)
        left = len(self.waiting) + len(self.running)
        line = (f"campaign: {self.done} done, {len(self.failures)} failed, "
                f"{len(self.running)} running, {len(self.waiting)} waiting")
        if left:
            rate = (time.monotonic() - self.start) / finished
            line += f"; about {_duration(rate * left)} left"
        print(line, flush=True)


def _first_line(e: Exception) -> str:
    """The exception's first line, at most 300 characters (Ray's messages run long)."""
    text = str(e).strip()
    return text.splitlines()[0][:300] if text else ""


def _record_retry(out: str, task: CampaignTask, attempt: int, why: str) -> None:
    path = os.path.join(out, RETRIES_FILE)
    new = not os.path.exists(path)
    with open(path, "a", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        if new:
            w.writerow(["cell", "attempt", "reason"])
        w.writerow([os.path.relpath(task.dir, out), attempt, why])


def run_on_ray(
    tasks: Sequence[CampaignTask],
    address: Optional[str] = None,
    num_cpus: Optional[int] = None,
    *,
    out: Optional[str] = None,
    max_retries: int = 2,
) -> List[Failure]:
    """Runs every task as a Ray task in a fresh worker process on any node; returns the failures.

    Connects to the cluster at ``address`` (e.g. ``"auto"``), or starts a local Ray with
    ``num_cpus`` CPUs when ``address`` is ``None`` and Ray is not initialised yet. Inputs and
    results travel through Ray (the module's doc); a task whose worker or node is lost runs
    again up to ``max_retries`` times, recorded in ``<out>/retries.csv`` when ``out`` is given.
    """
    import ray

    started = False
    if not ray.is_initialized():
        if address is None:
            ray.init(num_cpus=num_cpus, include_dashboard=False)
        else:
            ray.init(address=address)
        started = True
    # Ctrl-C is noted and acted on between waits (see `_Stop`); a signal handler can only be
    # set from the main thread, elsewhere Python's own KeyboardInterrupt stays.
    stop = _Stop() if threading.current_thread() is threading.main_thread() else None
    previous = signal.signal(signal.SIGINT, stop) if stop is not None else None
    try:
        return _Run(ray, tasks, out, max_retries, stop).run()
    finally:
        if stop is not None:
            signal.signal(signal.SIGINT, previous if previous is not None else signal.SIG_DFL)
        if started:
            ray.shutdown()
