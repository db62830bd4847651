"""``actorbt topic list | echo TOPIC | hz TOPIC``: the robot's topics, as ``ros2 topic``
shows them (there is no ``ros2`` command from pip).

    actorbt topic list [-t]                          # names (and types) of every topic
    actorbt topic echo /odom [--once] [--json]       # each message as YAML (ROS field names)
    actorbt topic hz /scan [--window N] [--count N]  # its rate, every second
    ... --bus ros                                    # over ROS 2: a robot, or an
                                                     # `actorbt sim run --bus ros` elsewhere

Where the topics are: on the local bus (the default of actorbt.yaml), this process builds
the runtime actorbt.yaml names (subsystems and world; not the trees) and looks at its bus.
The runtime's clock is the one actorbt.yaml names: on the virtual clock the simulator
runs as fast as it can while ``echo`` and ``hz`` wait, so their times (the rate, the
reports every second, ``--timeout``) are sim time; ``--clock wall`` measures wall time.
With ``--bus ros`` nothing is started here: a node listens on the ROS graph, on the wall
clock, and subscribes with the QoS the topic's publishers offer (a best-effort /scan is
heard).

Exit status: 0; 1 when ``--timeout`` passed without a message; 2 for an unknown topic
(with close matches) or a bad option; 130 on Ctrl-C.

Nothing here imports ROS, the simulator or the robot until a command runs.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import difflib
import json
import math
import os
import signal
import sys
import threading
import time
from types import FrameType
from typing import TYPE_CHECKING, Any, Callable, Iterable, cast

from bt_engine.errors import ActorbtError

if TYPE_CHECKING:
    from bt_engine.bus.transport import TopicInfo
    from bt_ros.transport import RosTransport
    from .app import App

#: exit status of a command ended with Ctrl-C
INTERRUPTED = 130
#: how far the virtual clock runs between two looks at the messages [s, runtime clock]
STEP = 0.05
#: messages kept for the printer at most (older ones are dropped, and counted)
BACKLOG = 1000
#: how often hz reports [s, runtime clock]
REPORT_PERIOD = 1.0


class UnknownTopicError(ActorbtError, LookupError):
    """No topic of that name on the bus."""


def register(sub: argparse._SubParsersAction, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser(
        "topic",
        help="the robot's topics: list, echo, hz (like ros2 topic)",
        description="Look at the robot's topics as `ros2 topic` does: list them, print their "
        "messages, measure their rates. On the local bus they are the topics of "
        "the runtime actorbt.yaml names (its subsystems and world, started here); "
        "with --bus ros, those of the ROS graph (a robot, or an "
        "`actorbt sim run --bus ros` in another process).",
    )
    tsub = p.add_subparsers(dest="topic_command", metavar="TOPIC_COMMAND")
    tsub.required = True

    wait_help = "With --bus ros: wait up to S seconds for the topic and a publisher of it to be discovered (default 5)."
    q = tsub.add_parser(
        "list",
        help="list the topics (with -t, their types)",
        description="List every topic on the bus, one per line; with -t, each with its type in brackets.",
    )
    q.add_argument(
        "-t", "--show-types", action="store_true", help="Show each topic's type after its name, as [package/msg/Name]."
    )
    q.add_argument(
        "--json",
        action="store_true",
        help="Print a JSON list of the topics: name, type, publishers, subscribers and the QoS the publishers offer.",
    )
    q.add_argument(
        "--wait",
        type=float,
        default=1.0,
        metavar="S",
        help="With --bus ros: discover the ROS graph for S seconds before listing "
        "(default 1; a robot over Wi-Fi may need more).",
    )
    common(q)
    q.set_defaults(func=cmd_list)

    e = tsub.add_parser(
        "echo",
        help="print a topic's messages: TOPIC [--once] [--json]",
        description="Print each message of a topic as it arrives: as YAML with the ROS field "
        "names, followed by '---' (with --json, one JSON object per line). Long "
        "arrays and strings are cut after 128 items, as ros2 does; --full prints "
        "them whole and --no-arr leaves arrays of numbers out.",
    )
    e.add_argument("topic", help="The topic's name, e.g. /odom (a name without the leading slash is taken from /).")
    e.add_argument("--once", action="store_true", help="Print one message, then exit.")
    e.add_argument("--count", type=_positive_int, metavar="N", help="Exit after N messages.")
    e.add_argument(
        "--json", action="store_true", help="Print each message as one line of JSON (NaN and infinities become null)."
    )
    e.add_argument(
        "--no-arr",
        action="store_true",
        help="Leave arrays of numbers, booleans and bytes out, printing only their "
        "type and length (an image's pixels, a scan's ranges); arrays of "
        "messages and strings are printed (the transforms of /tf_static, a "
        "JointState's names), unlike ros2's --no-arr, which leaves them out too.",
    )
    e.add_argument(
        "--truncate",
        type=_positive_int,
        default=128,
        metavar="N",
        help="Keep the first N items of each array and characters of each string (default 128).",
    )
    e.add_argument("--full", action="store_true", help="Print arrays and strings whole.")
    e.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="Stop after S seconds on the runtime clock; exit status 1 if no message came.",
    )
    e.add_argument("--wait", type=float, default=5.0, metavar="S", help=wait_help)
    common(e)
    e.set_defaults(func=cmd_echo)

    h = tsub.add_parser(
        "hz",
        help="print a topic's rate every second: TOPIC [--window N]",
        description="Print a topic's rate every second, as `ros2 topic hz` does: the average "
        "rate, the shortest and longest interval, their standard deviation and "
        "the number of messages in the window. Times are on the runtime clock: "
        "sim time on the virtual clock, wall time with --clock wall or --bus ros.",
    )
    h.add_argument("topic", help="The topic's name, e.g. /scan (a name without the leading slash is taken from /).")
    h.add_argument(
        "--window",
        type=_positive_int,
        default=10000,
        metavar="N",
        help="Compute the rate over the last N messages (default 10000).",
    )
    h.add_argument("--count", type=_positive_int, metavar="N", help="Exit after N messages, with a last report.")
    h.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="Exit after S seconds on the runtime clock, with a last report; exit status 1 if no message came.",
    )
    h.add_argument("--wait", type=float, default=5.0, metavar="S", help=wait_help)
    common(h)
    h.set_defaults(func=cmd_hz)


def _positive_int(text: str) -> int:
    n = int(text)
    if n < 1:
        raise argparse.ArgumentTypeError(f"expected a positive count, got {text}")
    return n


# -- the bus -----------------------------------------------------------------------------
class Bus:
    """The runtime whose bus the command looks at, and how to close it."""

    def __init__(self, args: argparse.Namespace, app: App) -> None:
        kind = getattr(args, "bus", None) or app.cfg.transport
        self.ros = kind == "ros"
        world = getattr(args, "world", None)
        if self.ros and world not in (None, "none"):
            raise ActorbtError(
                "--world starts a world in this process; with --bus ros the "
                "topic commands only listen (start the world with "
                "`actorbt sim run --bus ros`)"
            )
        if self.ros and getattr(args, "clock", None) == "virtual":
            raise ActorbtError("--clock virtual needs the local bus: ROS messages arrive in real time")
        # no trees (they use no topics); with --bus ros, nothing of actorbt.yaml at all
        cfg = dataclasses.replace(app.cfg, trees=None)
        if self.ros:
            cfg = dataclasses.replace(cfg, subsystems={}, world=None)
        self.app = type(app)(argparse.Namespace(**{**vars(args), "bus": kind}), cfg)
        self.rt = self.app.runtime(clock="wall" if self.ros else None, with_world=not self.ros)
        self.virtual = bool(self.rt.clock.virtual)

    @property
    def where(self) -> str:
        clock = "sim time: the virtual clock" if self.virtual else "wall time"
        return f"{'ROS' if self.ros else 'local'} bus, {clock}"

    def topics(self, wait: float = 0.0, until: Callable[[list[TopicInfo]], bool] | None = None) -> list[TopicInfo]:
        """The bus's topics; over ROS after ``wait`` seconds of discovery (or as soon as
        ``until(topics)`` holds)."""
        if not self.ros:
            return self.rt.run_on_hub(self.rt.bus.topics)
        deadline = time.monotonic() + wait
        while True:
            found = self.rt.bus.topics()
            if (until is not None and until(found)) or time.monotonic() >= deadline:
                return found
            time.sleep(0.1)

    def close(self) -> None:
        self.app.close(self.rt)


def topic_name(text: str) -> str:
    return text if text.startswith("/") else "/" + text


def find_topic(topics: list[TopicInfo], name: str) -> TopicInfo:
    """The topic ``name`` of ``topics``; else UnknownTopicError with close matches."""
    for t in topics:
        if t.name == name:
            return t
    raise UnknownTopicError(unknown_topic_message(name, [t.name for t in topics]))


def unknown_topic_message(name: str, names: list[str]) -> str:
    close = difflib.get_close_matches(name, names, n=3, cutoff=0.6)
    stem = name.strip("/").rsplit("/", 1)[-1]
    close += [n for n in names if stem and stem in n and n not in close][:3]
    if close:
        hint = f"; did you mean {', '.join(close[:4])}?"
    elif names:
        hint = "; `actorbt topic list` shows the topics"
    else:
        hint = "; there are no topics on the bus"
    return f"unknown topic {name}{hint}"


class Tap:
    """The messages of one topic, stamped with the runtime clock as they arrive on the
    hub, handed to the calling thread. ``keep=False`` keeps only the stamps (``hz``)."""

    def __init__(self, bus: Bus, name: str, msg_type: type, qos: Any, *, keep: bool = True) -> None:
        self._rt = bus.rt
        self._keep = keep
        self._lock = threading.Lock()
        self._items: collections.deque = collections.deque()
        self._arrived = threading.Event()
        self.dropped = 0
        self._sub = bus.rt.run_on_hub(bus.rt.bus.subscribe, name, msg_type, self._on_message, qos)

    def _on_message(self, msg: Any) -> None:  # hub
        item = (self._rt.now(), msg if self._keep else None)
        with self._lock:
            if self._keep and len(self._items) >= BACKLOG:
                self._items.popleft()
                self.dropped += 1
            self._items.append(item)
        self._arrived.set()

    def take(self) -> list[tuple[float, Any]]:
        with self._lock:
            items = list(self._items)
            self._items.clear()
            self._arrived.clear()
        return items

    def run_until(self, t: float, virtual: bool) -> list[tuple[float, Any]]:
        """Let the runtime run until ``t`` on its clock (on the wall clock: until then or
        the next message) and return what arrived."""
        rt = self._rt
        delay = t - rt.now()
        if virtual:
            if delay > 0:
                rt.call("sleep", delay)  # a live transaction: the virtual clock runs
        elif delay > 0:
            self._arrived.wait(delay)
        return self.take()

    def close(self) -> None:
        try:
            self._rt.run_on_hub(self._sub.close)
        except Exception:  # the runtime is closing anyway
            pass


def _subscribe(bus: Bus, args: argparse.Namespace, what: str, *, keep: bool) -> Tap:
    """A tap on the topic the command names, after checking that it exists."""
    from bt_engine.bus.messages import message_class

    name = topic_name(args.topic)
    topics = bus.topics(args.wait, until=lambda found: any(t.name == name and t.publishers for t in found))
    try:
        info = find_topic(topics, name)
    except UnknownTopicError as e:
        if not bus.ros:
            raise
        domain = os.environ.get("ROS_DOMAIN_ID", "0")
        scope = os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
        raise UnknownTopicError(
            f"{e} (on the ROS graph after {args.wait:g} s of discovery: "
            f"ROS_DOMAIN_ID {domain}, discovery range {scope})"
        ) from None
    msg_type = message_class(info.type.split(",")[0].strip())
    qos = cast("RosTransport", bus.rt.bus).matching_qos(name) if bus.ros else 10
    print(f"actorbt topic {what}: {name} [{info.type}] ({bus.where})", file=sys.stderr, flush=True)
    if not info.publishers:
        print(
            f"actorbt topic {what}: nothing publishes {name} yet; waiting (Ctrl-C stops)", file=sys.stderr, flush=True
        )
    return Tap(bus, name, msg_type, qos, keep=keep)


def _run(args: argparse.Namespace, app: App, body: Callable[[Bus], int]) -> int:
    """Build the bus, run ``body``, close everything; Ctrl-C (or SIGTERM) is exit status
    130, after a clean close (a ROS node leaves no shared memory behind)."""
    main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGTERM) if main else None
    if main:
        signal.signal(signal.SIGTERM, _interrupt)
    bus = None
    try:
        bus = Bus(args, app)
        return body(bus)
    except KeyboardInterrupt:
        print("actorbt: interrupted", file=sys.stderr, flush=True)
        return INTERRUPTED
    finally:
        try:
            if bus is not None:
                bus.close()
        except KeyboardInterrupt:
            pass
        finally:
            if main:
                signal.signal(signal.SIGTERM, previous)


def _interrupt(signum: int, frame: FrameType | None) -> None:
    raise KeyboardInterrupt


# -- list --------------------------------------------------------------------------------
def cmd_list(args: argparse.Namespace, app: App) -> int:
    def body(bus: Bus) -> int:
        topics = bus.topics(args.wait)
        if args.json:
            print(json.dumps([t._asdict() for t in topics], indent=2))
            return 0
        for t in topics:
            print(f"{t.name} [{t.type}]" if args.show_types else t.name)
        return 0

    return _run(args, app, body)


# -- echo --------------------------------------------------------------------------------
def cmd_echo(args: argparse.Namespace, app: App) -> int:
    from bt_engine.bus.messages import to_plain

    count = 1 if args.once else args.count
    truncate = None if args.full else args.truncate

    def show(msg: Any) -> None:
        data = to_plain(msg, truncate=truncate, arrays=not args.no_arr, finite=args.json)
        if args.json:
            print(json.dumps(data, allow_nan=False), flush=True)
        else:
            print(format_yaml(data), end="", flush=True)
            print("---", flush=True)

    def body(bus: Bus) -> int:
        tap = _subscribe(bus, args, "echo", keep=True)
        rt = bus.rt
        end = rt.now() + args.timeout if args.timeout is not None else math.inf
        shown = 0
        try:
            while True:
                for _, msg in tap.run_until(min(rt.now() + STEP, end), bus.virtual):
                    show(msg)
                    shown += 1
                    if count is not None and shown >= count:
                        return 0
                if rt.now() >= end:
                    break
        finally:
            if tap.dropped:
                print(f"actorbt topic echo: {tap.dropped} messages dropped (printing fell behind)", file=sys.stderr)
            tap.close()
        if not shown:
            print(
                f"actorbt topic echo: no message on {topic_name(args.topic)} within {args.timeout:g} s", file=sys.stderr
            )
            return 1
        return 0

    return _run(args, app, body)


def format_yaml(data: Any) -> str:
    """A message's plain data as YAML: fields in message order, one per line, as ``ros2
    topic echo`` prints them; a list of numbers or strings on one (wrapped) line."""
    import yaml

    class Dumper(yaml.SafeDumper):
        pass

    def represent_list(dumper: yaml.SafeDumper, items: list) -> yaml.SequenceNode:
        flat = all(not isinstance(v, (dict, list)) for v in items)
        return dumper.represent_sequence("tag:yaml.org,2002:seq", items, flow_style=flat)

    Dumper.add_representer(list, represent_list)
    return yaml.dump(data, Dumper=Dumper, default_flow_style=False, sort_keys=False, width=100, allow_unicode=True)


# -- hz ----------------------------------------------------------------------------------
@dataclasses.dataclass
class Rate:
    """The statistics ``ros2 topic hz`` prints, over the intervals of a window."""

    rate: float
    min: float
    max: float
    std_dev: float
    window: int

    @classmethod
    def of(cls, stamps: Iterable[float]) -> "Rate | None":
        t = list(stamps)
        deltas = [b - a for a, b in zip(t, t[1:])]
        if not deltas:
            return None
        mean = sum(deltas) / len(deltas)
        std = math.sqrt(sum((d - mean) ** 2 for d in deltas) / len(deltas))
        return cls(1.0 / mean if mean > 0 else 0.0, min(deltas), max(deltas), std, len(t))

    def text(self, clock: str) -> str:
        return (
            f"average rate: {self.rate:.3f} ({clock})\n"
            f"\tmin: {self.min:.3f}s max: {self.max:.3f}s std dev: {self.std_dev:.5f}s "
            f"window: {self.window}"
        )


def cmd_hz(args: argparse.Namespace, app: App) -> int:
    def body(bus: Bus) -> int:
        tap = _subscribe(bus, args, "hz", keep=False)
        rt = bus.rt
        clock = "sim time" if bus.virtual else "wall time"
        stamps: collections.deque = collections.deque(maxlen=args.window)
        end = rt.now() + args.timeout if args.timeout is not None else math.inf
        received = 0
        fresh = False  # messages since the last report
        next_report = rt.now() + REPORT_PERIOD

        def report() -> None:
            nonlocal fresh
            rate = Rate.of(stamps) if fresh else None
            print(rate.text(clock) if rate is not None else "no new messages", flush=True)
            fresh = False

        try:
            while True:
                until = min(next_report, end)
                for t, _ in tap.run_until(until, bus.virtual):
                    stamps.append(t)
                    received += 1
                    fresh = True
                    if args.count is not None and received >= args.count:
                        report()
                        return 0
                now = rt.now()
                if now >= end:
                    break
                if now >= next_report:
                    report()
                    while next_report <= now:
                        next_report += REPORT_PERIOD
        finally:
            tap.close()
        if received:
            if fresh:
                report()
            return 0
        print(f"actorbt topic hz: no message on {topic_name(args.topic)} within {args.timeout:g} s", file=sys.stderr)
        return 1

    return _run(args, app, body)
