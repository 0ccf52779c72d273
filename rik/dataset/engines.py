"""Where units of work run: in this process, in local worker processes, or on a Ray cluster.

An engine takes :class:`Job` s (a module-level function of ``(catalog, arg)`` and its argument) and hands back
:class:`Done` s as they finish, in any order. A job's own error comes back as a one-line message in ``Done.error``
(the builder retries and records it); the engine never raises for one. Jobs return small records (paths, counts,
seconds), never frames: on Ray the object store is small in containers.

Ray (``RayEngine``) is imported only when asked for. CPU stages run as Ray tasks; render jobs (``Job.renders``)
run on long-lived actors when the cluster has GPUs, or when asked (``render_actors``): an actor keeps its process,
its imports (seconds each) and Dr.Jit's in-memory kernel cache from one episode to the next, where a GPU task would
get a fresh process per call. MuJoCo's GL context is still made per episode (0.06-0.14 s on llvmpipe, measured).
One renderer per actor, at most :data:`RENDERERS_PER_GPU` per GPU (MuJoCo's EGL hangs with many concurrent
renderers on one GPU, mujoco#3444).
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from rik.errors import RikError

if TYPE_CHECKING:
    from rik.registry.catalog import Catalog

RENDERERS_PER_GPU = 4
"""Render actors that share one GPU (each holds one renderer)."""
ACTOR_LOSSES = 3
"""Times a render job whose actor was lost is sent again (as a task) before it counts as failed."""
RAY_CONNECT_TIMEOUT_S = 30
"""How long ``--ray ADDRESS`` waits for the cluster to answer, s (the environment variable
``RIK_RAY_CONNECT_TIMEOUT`` overrides it)."""


def ray_connect_timeout() -> float:
    """How long ``--ray ADDRESS`` waits for the cluster to answer, s: ``RIK_RAY_CONNECT_TIMEOUT`` or the default."""
    text = os.environ.get("RIK_RAY_CONNECT_TIMEOUT", "").strip()
    if not text:
        return RAY_CONNECT_TIMEOUT_S
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0 < value < float("inf"):
        raise RikError(f"RIK_RAY_CONNECT_TIMEOUT: a number of seconds above 0 (got {text!r})")
    return value


@dataclass(frozen=True)
class Job:
    """One unit of work: ``fn(catalog, arg)`` where ``fn`` is a module-level function (it is pickled)."""

    key: str
    stage: str
    fn: Callable[[Catalog, Any], Any]
    arg: Any
    renders: bool = False
    """It renders frames (a GPU job where the cluster has GPUs)."""


@dataclass(frozen=True)
class Done:
    job: Job
    value: Any = None
    error: str | None = None
    """One line, when the job failed."""


class Engine(Protocol):
    name: str
    workers: int
    """Jobs that can run at once (for estimates and messages)."""

    def submit(self, job: Job) -> None: ...

    def wait(self) -> list[Done]:
        """Block until at least one submitted job has finished; those that have, in any order."""
        ...

    def pending(self) -> int: ...

    def close(self) -> None: ...


def error_line(exc: BaseException) -> str:
    """One line for a job's error: a RikError's own message, else the exception's type and first line."""
    if isinstance(exc, RikError):
        return str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    text = str(exc).strip().splitlines()
    return f"{type(exc).__name__}: {text[0]}" if text else type(exc).__name__


def run_job(catalog: Catalog, fn: Callable[[Catalog, Any], Any], arg: Any) -> tuple[Any, str | None]:
    """``(fn(catalog, arg), None)``, or ``(None, message)`` when it raised: errors cross process boundaries as
    text, so nothing unpicklable ever travels back."""
    try:
        return fn(catalog, arg), None
    except Exception as exc:  # a job's failure is data for the builder, whatever its type
        return None, error_line(exc)


class InlineEngine:
    """Runs each job here, one at a time, in submission order."""

    name = "inline"
    workers = 1

    def __init__(self, catalog: Catalog):
        self.catalog = catalog
        self.queue: deque[Job] = deque()

    def submit(self, job: Job) -> None:
        self.queue.append(job)

    def pending(self) -> int:
        return len(self.queue)

    def wait(self) -> list[Done]:
        job = self.queue.popleft()
        value, error = run_job(self.catalog, job.fn, job.arg)
        return [Done(job, value, error)]

    def close(self) -> None:
        self.queue.clear()


def _worker_job(fn: Callable[[Catalog, Any], Any], arg: Any) -> tuple[Any, str | None]:
    from rik import workers

    assert workers._CATALOG is not None
    return run_job(workers._CATALOG, fn, arg)


class ProcessEngine:
    """Runs jobs in ``workers`` spawned processes that load the catalog once and exit with this one
    (:func:`rik.workers.exit_with_parent`, so a ``kill -9`` of the build leaves no worker behind). A worker
    that dies (a crash in C code, the OOM killer) fails the jobs it may have held; the pool is started anew."""

    name = "local processes"

    def __init__(self, workers: int, overlays: Sequence[Path] = ()):
        self.workers = workers
        self.overlays = list(overlays)
        self.futures: dict[Any, Job] = {}
        self.pool = self._pool()

    def _pool(self) -> Any:
        from rik.workers import worker_pool

        return worker_pool(self.workers, self.overlays)

    def submit(self, job: Job) -> None:
        self.futures[self.pool.submit(_worker_job, job.fn, job.arg)] = job

    def pending(self) -> int:
        return len(self.futures)

    def wait(self) -> list[Done]:
        from concurrent.futures import FIRST_COMPLETED
        from concurrent.futures import wait as wait_futures
        from concurrent.futures.process import BrokenProcessPool

        finished, _ = wait_futures(list(self.futures), return_when=FIRST_COMPLETED)
        out = []
        broken = False
        for f in finished:
            job = self.futures.pop(f)
            try:
                value, error = f.result()
            except BrokenProcessPool:
                broken = True
                value, error = None, "a worker process died while running it (killed, or a crash in C code)"
            out.append(Done(job, value, error))
        if broken:  # the pool is unusable: its other jobs are lost too; start a new pool
            for job in list(self.futures.values()):
                out.append(Done(job, None, "a worker process died while this job was queued or running"))
            self.futures.clear()
            self.pool.shutdown(wait=False, cancel_futures=True)
            self.pool = self._pool()
        return out

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)
        self.futures.clear()


def local_engine(catalog: Catalog, workers: int, overlays: Sequence[Path] = ()) -> Engine:
    """This process for one worker, else a pool of processes."""
    return InlineEngine(catalog) if workers <= 1 else ProcessEngine(workers, overlays)


# ---- Ray ----------------------------------------------------------------------------------------------------------
_RAY_CATALOG: dict[tuple[str, ...], Catalog] = {}
"""Catalogs loaded in this Ray worker process, by overlay paths."""


def _ray_catalog(overlays: tuple[str, ...]) -> Catalog:
    if overlays not in _RAY_CATALOG:
        from rik.registry.load import load_catalog

        _RAY_CATALOG[overlays] = load_catalog([Path(p) for p in overlays])
    return _RAY_CATALOG[overlays]


def _ray_job(overlays: tuple[str, ...], fn: Callable[[Catalog, Any], Any], arg: Any) -> tuple[Any, str | None]:
    try:
        catalog = _ray_catalog(overlays)
    except Exception as exc:
        return None, f"cannot load the catalog on this node: {error_line(exc)}"
    return run_job(catalog, fn, arg)


class _RenderActor:
    """A long-lived process that renders (its class becomes a Ray actor in :class:`RayEngine`)."""

    def __init__(self, overlays: tuple[str, ...]):
        self.overlays = overlays

    def run(self, fn: Callable[[Catalog, Any], Any], arg: Any) -> tuple[Any, str | None]:
        return _ray_job(self.overlays, fn, arg)

    def node(self) -> str:
        """The id of the Ray node this actor lives on."""
        import ray

        return str(ray.get_runtime_context().get_node_id())


def ray_available() -> bool:
    """Whether the ``ray`` extra is installed (without importing it)."""
    from importlib.util import find_spec

    return find_spec("ray") is not None


def check_ray() -> None:
    """A clear error when ``--ray`` is asked for without the extra."""
    if not ray_available():
        raise RikError("--ray: Ray is not installed; install the extra with `uv sync --extra ray` (or "
                       "`pip install 'rik[ray]'`), or build on local processes without --ray")


class RayEngine:
    """Runs jobs on a Ray cluster: ``address`` is ``auto`` (the cluster this machine belongs to), ``local`` (start
    one on this machine for the build) or ``HOST:PORT``. Every node must see ``--out``, the work folder and the
    variants folder at the same paths (a shared file system): jobs pass paths, never data."""

    name = "ray"

    def __init__(self, address: str, overlays: Sequence[Path] = (), render_actors: int | None = None,
                 max_retries: int = 3):
        check_ray()
        os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")
        os.environ.setdefault("RAY_ENABLE_UV_RUN_RUNTIME_ENV", "0")
        import ray
        from ray._private import ray_constants

        # Under `uv run` Ray would otherwise ship the working folder to every worker and rerun uv there; rik's
        # nodes run the environment they were started from, and share files through the file system.
        ray_constants.RAY_ENABLE_UV_RUN_RUNTIME_ENV = os.environ["RAY_ENABLE_UV_RUN_RUNTIME_ENV"] not in ("0", "")

        self.ray = ray
        self.started_here = False
        if not ray.is_initialized():
            self._connect(address)
            self.started_here = True
        self.overlays = tuple(str(Path(p).resolve()) for p in overlays)
        resources = ray.cluster_resources()
        self.workers = max(1, int(resources.get("CPU", 1)))
        gpus = int(resources.get("GPU", 0))
        self.task = ray.remote(num_cpus=1, max_retries=max_retries)(_ray_job)
        self.actors: list[Any] = []
        count = render_actors if render_actors is not None else gpus * RENDERERS_PER_GPU
        if count:
            options: dict[str, Any] = {"num_cpus": 0, "max_restarts": -1, "max_task_retries": max_retries,
                                       "scheduling_strategy": "SPREAD"}  # over nodes (and GPUs)
            if gpus:
                options["num_gpus"] = 1.0 / RENDERERS_PER_GPU
            actor = ray.remote(**options)(_RenderActor)
            self.actors = [actor.remote(self.overlays) for _ in range(count)]
        self.calls: dict[Any, Job] = {}
        self.next_actor = 0
        self.actor_losses: dict[str, int] = {}

    def _connect(self, address: str) -> None:
        ray = self.ray
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False, "logging_level": "ERROR"}
        if address == "local":
            ray.init(**kwargs)
            return
        import threading

        result: list[BaseException | None] = []

        def connect() -> None:
            try:
                ray.init(address=address, **kwargs)
                result.append(None)
            except BaseException as exc:  # reported below as one line
                result.append(exc)

        thread = threading.Thread(target=connect, daemon=True)
        thread.start()
        timeout = ray_connect_timeout()
        thread.join(timeout)
        if not result:
            raise RikError(f"--ray {address}: no Ray cluster answered within {timeout:g} s; start one "
                           "(`ray start --head`) or give the head's address as HOST:PORT")
        if result[0] is not None:
            raise RikError(f"--ray {address}: cannot connect to a Ray cluster: {error_line(result[0])}")

    def submit(self, job: Job) -> None:
        if job.renders and self.actors:
            actor = self.actors[self.next_actor % len(self.actors)]
            self.next_actor += 1
            ref = actor.run.remote(job.fn, job.arg)
        else:
            ref = self.task.remote(self.overlays, job.fn, job.arg)
        self.calls[ref] = job

    def pending(self) -> int:
        return len(self.calls)

    def wait(self) -> list[Done]:
        """The finished calls; a render call whose actor was lost with its node (or is restarting) is sent again
        as a task, up to :data:`ACTOR_LOSSES` times, without counting as an attempt of the unit."""
        from ray.exceptions import RayActorError

        out: list[Done] = []
        while not out and self.calls:
            ready, _ = self.ray.wait(list(self.calls), num_returns=1)
            for ref in ready:
                job = self.calls.pop(ref)
                try:
                    value, error = self.ray.get(ref)
                except RayActorError as exc:
                    lost = self.actor_losses.get(job.key, 0) + 1
                    self.actor_losses[job.key] = lost
                    if lost <= ACTOR_LOSSES:
                        self.calls[self.task.remote(self.overlays, job.fn, job.arg)] = job
                        continue
                    value, error = None, f"lost on the Ray cluster (its render actor): {error_line(exc)}"
                except Exception as exc:  # the task's worker or node was lost beyond Ray's own retries
                    value, error = None, f"lost on the Ray cluster: {error_line(exc)}"
                out.append(Done(job, value, error))
        return out

    def close(self) -> None:
        for ref, job in list(self.calls.items()):
            try:
                self.ray.cancel(ref, force=not (job.renders and self.actors))  # actor calls cannot be forced
            except Exception:  # already finished, or its node is gone: nothing to stop
                pass
        self.calls.clear()
        for actor in self.actors:
            self.ray.kill(actor)
        self.actors = []
        if self.started_here:
            self.ray.shutdown()
