"""`actorbt eval --ray`: the episodes of an evaluation as Ray tasks, on a Ray cluster or a
local Ray instance. Ray is optional (``pip install 'actorbt[cluster]'``): it is imported
here only, when ``--ray`` is asked for.

Every node runs the same code as a ``--jobs`` worker (:func:`demo.evaluate._run_job`, handed
over by the evaluation; one task per episode, one CPU each) and sends the
:class:`~demo.episode.Episode` back; the driver writes the CSV and the table as for
``--jobs``. The nodes need the project importable: the same environment installed on each
(``pip install 'actorbt[sim,planning,cluster]'``, or one container image), see
docs/evaluation.md.
"""

from __future__ import annotations

from typing import Any, Callable, Iterable, Iterator

from bt_engine.errors import ActorbtError

INSTALL = "pip install 'actorbt[cluster]'"


class RayUnavailable(ActorbtError, ImportError):
    """--ray without Ray installed."""


def _ray():
    try:
        import ray
    except ImportError as exc:
        raise RayUnavailable(f"--ray needs Ray, which is not installed: {INSTALL}") from exc
    return ray


class RayRunner:
    """A connection to Ray for one evaluation: ``with RayRunner(address) as r:
    for ep in r.run(jobs): ...``.

    ``address``: ``True`` or ``None`` for ``ray.init()`` (the cluster in ``RAY_ADDRESS``,
    else the one ``ray start`` started on this machine, else a new local instance);
    a string for ``ray.init(address=...)`` (``auto``, ``HOST:6379``, ``ray://HOST:10001``,
    ``local``). A Ray already initialised in this process (a test's ``ray.init(num_cpus=2)``)
    is used as it is and left running; one this runner started is shut down at the end.
    ``runtime_env``: Ray's runtime environment for the tasks (e.g. ``{"working_dir": ".",
    "env_vars": {...}}``), given to ``ray.init``.
    """

    def __init__(self, address: bool | str | None = True, runtime_env: dict | None = None) -> None:
        self.address = None if address is True or address in ("", None) else str(address)
        self.runtime_env = runtime_env
        self._started = False
        self.ray: Any = None

    def __enter__(self) -> "RayRunner":
        ray = self.ray = _ray()
        if not ray.is_initialized():
            kwargs: dict = {"address": self.address}
            if self.runtime_env:
                kwargs["runtime_env"] = self.runtime_env
            ray.init(**kwargs)
            self._started = True
        return self

    def __exit__(self, *exc) -> None:
        if self._started:
            self.ray.shutdown()
            self._started = False

    @property
    def slots(self) -> int:
        """How many episodes the cluster runs at once (its CPUs): for the time left."""
        return max(1, int(self.ray.cluster_resources().get("CPU", 1)))

    def describe(self) -> str:
        res = self.ray.cluster_resources()
        nodes = sum(1 for n in self.ray.nodes() if n.get("Alive"))
        return f"Ray: {nodes} node{'s' * (nodes != 1)}, {int(res.get('CPU', 0))} CPUs"

    def run(self, work: Iterable[tuple], run_job: Callable[[tuple], Any]) -> Iterator[Any]:
        """One Ray task per job (``num_cpus=1``) running ``run_job(job)``, which the caller
        hands over so that this module imports nothing of the evaluation; yields each
        Episode as it finishes. A task that raised raises here (an actorbt error as itself;
        any other as Ray's RayTaskError, which also is one of its class, with the remote
        traceback); the tasks not yet done are cancelled when the caller stops (an error,
        Ctrl-C)."""
        ray = self.ray
        task = ray.remote(num_cpus=1)(run_job)
        pending = [task.remote(job) for job in work]
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    try:
                        ep = ray.get(ref)
                    except ray.exceptions.RayTaskError as exc:
                        cause = getattr(exc, "cause", None)
                        if isinstance(cause, ActorbtError):  # a user's mistake: its message
                            raise cause from None
                        raise  # else Ray's, with the remote traceback
                    yield ep
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
