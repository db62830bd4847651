"""One rclpy Context, its nodes, and the one executor thread that serves them.

Each :class:`RosHost` owns a private ``rclpy.context.Context`` (never the global default
one), so several runtimes in one process coexist and shut down independently, and no
signal handlers are installed: Ctrl-C stays a ``KeyboardInterrupt`` of the main thread.

Threads:
- The executor thread runs every rclpy callback. Callbacks hand their work to the
  runtime hub with ``rt.call_soon_threadsafe``.
- Code on other threads (the hub, a CLI) hands work to the executor thread with
  :meth:`RosHost.post`, in FIFO order, or :meth:`RosHost.call` to wait for a result.
  rclpy's action client keeps no lock around its request tables, so goals, cancels and
  result requests are always sent from the executor thread.
- The executor thread may wait for the hub (``rt.run_on_hub``), so the hub never waits
  for the executor thread: from the hub, only ``post``, never ``call``.

Discovery: ``ROS_AUTOMATIC_DISCOVERY_RANGE`` defaults to ``LOCALHOST`` (set before the
context is created, unless the environment already says otherwise), so no discovery
traffic leaves the machine. On this machine only (range ``LOCALHOST``), and unless a Fast
DDS profile is configured (``FASTRTPS_DEFAULT_PROFILES_FILE``,
``FASTDDS_DEFAULT_PROFILES_FILE`` or ``DEFAULT_FASTRTPS_PROFILES.xml`` in the working
folder), each participant re-announces itself every :data:`ANNOUNCE_PERIOD` seconds
instead of Fast DDS's 3 s: a process that joins (``actorbt rcall``, ``actorbt goal``)
often learns of the running ones only from their next announcement, so a cold client
waited up to 3 s for discovery (about 1 s on average, measured on loopback), and now a
few tenths of a second. The profile is written to the temporary folder and named in
``FASTRTPS_DEFAULT_PROFILES_FILE`` for this process and its children.
"""

from __future__ import annotations

import collections
import concurrent.futures
import logging
import os
import pathlib
import tempfile
import threading
import uuid
from typing import TYPE_CHECKING, Callable, TypedDict, TypeVar

from bt_engine.errors import ActorbtError

if TYPE_CHECKING:
    from rclpy.node import Node
    from rclpy.parameter import Parameter

T = TypeVar("T")


class _NodeOptions(TypedDict, total=False):
    """The keyword arguments of ``rclpy.create_node`` that create_node sets."""

    enable_rosout: bool
    parameter_overrides: list[Parameter]
    cli_args: list[str]


log = logging.getLogger("actorbt.ros")


class RosClosedError(ActorbtError, RuntimeError):
    """The ROS host (context, executor) was closed."""


#: how often a participant re-announces itself when discovery stays on this machine [s]
ANNOUNCE_PERIOD = 0.25

_PROFILE = """\
<?xml version="1.0" encoding="UTF-8"?>
<!-- Written by actorbt (bt_ros/host.py) for DDS discovery on this machine only:
     each participant re-announces itself every {period:g} s (Fast DDS: 3 s), so a process
     that joins discovers the running ones within that time. -->
<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <profiles>
    <participant profile_name="actorbt_localhost" is_default_profile="true">
      <rtps>
        <builtin>
          <discovery_config>
            <leaseAnnouncement><sec>{sec}</sec><nanosec>{nanosec}</nanosec></leaseAnnouncement>
          </discovery_config>
        </builtin>
      </rtps>
    </participant>
  </profiles>
</dds>
"""
_PROFILE_VARS = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")


def default_environment() -> None:
    """Keep DDS discovery on this machine unless the environment chose otherwise, and
    there, announce often (see the module docstring). Before the first context."""
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    if os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"].strip().upper() != "LOCALHOST":
        return
    if any(os.environ.get(v) for v in _PROFILE_VARS) or os.path.exists("DEFAULT_FASTRTPS_PROFILES.xml"):
        return
    path = _write_profile(ANNOUNCE_PERIOD)
    if path is not None:
        os.environ["FASTRTPS_DEFAULT_PROFILES_FILE"] = path


def _write_profile(period: float) -> str | None:
    """The Fast DDS profile file for ``period``, written once per user; None if it cannot be."""
    sec = int(period)
    text = _PROFILE.format(period=period, sec=sec, nanosec=int(round((period - sec) * 1e9)))
    uid = os.getuid() if hasattr(os, "getuid") else 0
    path = pathlib.Path(tempfile.gettempdir()) / f"actorbt-{uid}-fastdds-localhost.xml"
    try:
        if path.is_file() and path.read_text() == text:
            return str(path)
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, path)
    except OSError as e:
        log.debug("cannot write the Fast DDS profile %s: %s", path, e)
        return None
    return str(path)


class RosHost:
    """A private rclpy Context with a single-threaded executor spinning in its own thread.

    Args:
        name: used for the thread name and in log messages.
        domain_id: ROS domain; ``None`` takes ``ROS_DOMAIN_ID`` (or 0).
    """

    def __init__(self, name: str = "actorbt", *, domain_id: int | None = None) -> None:
        default_environment()
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor

        self.name = name
        #: distinguishes this host's thread and default node names from other hosts'
        self.id = uuid.uuid4().hex[:8]
        self.context = Context()
        # Context.init (not rclpy.init): no signal handlers, no ROS args from sys.argv.
        self.context.init(args=[], domain_id=domain_id)
        self.executor = SingleThreadedExecutor(context=self.context)
        self._nodes: list[Node] = []
        self._lock = threading.Lock()
        self._queue: collections.deque[tuple[Callable[..., object], tuple[object, ...]]] = collections.deque()
        self._drain_scheduled = False
        self._stopping = False
        self._closed = False
        self._thread = threading.Thread(target=self._spin, name=f"actorbt-ros-{name}-{self.id}", daemon=True)
        self._thread.start()

    # -- nodes -------------------------------------------------------------------------
    def create_node(
        self, name: str, namespace: str | None = None, *, lean: bool = False, ros_args: list[str] | None = None
    ) -> Node:
        """A node in this context, spun by this host's executor.

        ``lean``: a client's node, without ``/rosout`` and the type description service
        (``~/get_type_description``), which cost about 0.1 s to create.
        ``ros_args``: rclpy's command-line arguments for this node only, e.g.
        ``["-r", "__ns:=/robot1"]`` (``--ros-args`` is added in front when missing).

        Raises:
            ValueError: ``ros_args`` that rcl does not understand."""
        import rclpy
        import rclpy.exceptions

        self._check_open()
        options: _NodeOptions = {}
        if lean:
            from rclpy.parameter import Parameter

            options = {
                "enable_rosout": False,
                "parameter_overrides": [Parameter("start_type_description_service", value=False)],
            }
        if ros_args:
            options["cli_args"] = ros_args if ros_args[0] == "--ros-args" else ["--ros-args", *ros_args]
        try:
            node = rclpy.create_node(
                name, context=self.context, namespace=namespace, start_parameter_services=False, **options
            )
        except rclpy.exceptions.InvalidNamespaceException as e:
            raise ValueError(f"invalid namespace {namespace!r}: {e}") from None
        # rclpy has no stub of its pybind11 module, where RCLError is defined
        except rclpy._rclpy_pybind11.RCLError as e:  # type: ignore[attr-defined]  # unknown --ros-args
            raise ValueError(f"invalid ROS arguments {' '.join(ros_args or [])!r}: {e}") from None
        with self._lock:
            self._nodes.append(node)
        self.executor.add_node(node)
        return node

    def destroy_node(self, node: Node) -> None:
        """Remove ``node`` from the executor and destroy it (on the executor thread)."""
        with self._lock:
            if node not in self._nodes:
                return
            self._nodes.remove(node)

        def destroy() -> None:
            self.executor.remove_node(node)
            _destroy_node(node)

        if self._stopping:
            destroy()
        else:
            self.call(destroy)

    # -- hand-over to the executor thread ------------------------------------------
    def in_executor_thread(self) -> bool:
        return threading.current_thread() is self._thread

    def post(self, fn: Callable[..., object], *args: object) -> None:
        """Run ``fn(*args)`` on the executor thread soon, after earlier posts. Any thread.

        Raises:
            RosClosedError: the host is closing.
        """
        with self._lock:
            if self._stopping:
                raise RosClosedError(f"ROS host {self.name} is closed")
            self._queue.append((fn, args))
            if self._drain_scheduled:
                return
            self._drain_scheduled = True
            self.executor.create_task(self._drain)

    def call(self, fn: Callable[..., T], *args: object, timeout: float = 10.0) -> T:
        """Run ``fn(*args)`` on the executor thread and return its result."""
        if self.in_executor_thread():
            return fn(*args)
        fut: concurrent.futures.Future[T] = concurrent.futures.Future()

        def run() -> None:
            try:
                fut.set_result(fn(*args))
            except BaseException as e:  # handed to the caller
                fut.set_exception(e)

        self.post(run)
        done, _ = concurrent.futures.wait([fut], timeout)
        if not done:
            raise RosClosedError(f"ROS host {self.name}: executor did not answer in {timeout:g} s")
        return fut.result()

    def flush(self, timeout: float = 1.0) -> bool:
        """Wait until everything posted so far has run. False on timeout or when closed."""
        try:
            self.call(lambda: None, timeout=timeout)
        except RosClosedError:
            return False
        return True

    def _drain(self) -> None:
        while True:
            with self._lock:
                if not self._queue:
                    self._drain_scheduled = False
                    return
                fn, args = self._queue.popleft()
            try:
                fn(*args)
            except Exception:
                log.exception("ROS host %s: posted call %s failed", self.name, getattr(fn, "__qualname__", fn))

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException, ShutdownException

        ex = self.executor
        while not self._stopping:
            try:
                ex.spin_once()
            except (ExternalShutdownException, ShutdownException):
                break
            except Exception:
                # One failing callback must not take the executor thread down.
                log.exception("ROS host %s: callback failed", self.name)

    # -- lifecycle -----------------------------------------------------------------------
    def _check_open(self) -> None:
        if self._stopping:
            raise RosClosedError(f"ROS host {self.name} is closed")

    @property
    def closed(self) -> bool:
        return self._stopping

    def close(self, timeout: float = 5.0) -> None:
        """Run what was posted, stop the executor thread, destroy every node, shut the
        context down. Idempotent. Fast DDS removes its shared-memory segments then."""
        if self._closed:
            return
        self._closed = True
        if threading.current_thread() is not self._thread:
            self.flush(timeout=1.0)
        with self._lock:
            self._stopping = True
            # A task is work: spin_once returns after it and the loop sees _stopping.
            self.executor.create_task(lambda: None)
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)
            if self._thread.is_alive():
                log.warning("ROS host %s: executor thread did not stop in %g s", self.name, timeout)
        with self._lock:
            nodes, self._nodes = self._nodes, []
        for node in nodes:
            try:
                self.executor.remove_node(node)
                _destroy_node(node)
            except Exception:
                log.exception("ROS host %s: destroying node failed", self.name)
        try:
            self.executor.shutdown(timeout_sec=0)
        except Exception:
            log.exception("ROS host %s: executor shutdown failed", self.name)
        self.context.try_shutdown()
        self.context.destroy()

    def __enter__(self) -> "RosHost":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<RosHost {self.name} {'closed' if self._stopping else 'open'}>"


def _destroy_node(node: Node) -> None:
    """Destroy a node and its waitables. ``Node.destroy_node`` leaves action clients and
    servers alive; their handles keep the node, and so the DDS participant (its
    threads and shared memory), alive until the process ends."""
    for waitable in list(node.waitables):
        destroy = getattr(waitable, "destroy", None)
        if destroy is not None:
            try:
                destroy()
            except Exception:
                log.exception("destroying %r failed", waitable)
    node.destroy_node()
