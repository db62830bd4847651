"""``actorbt serve``, ``actorbt goal``, ``actorbt rcall`` and ``actorbt rshell``.

    actorbt serve [--bus ros] [--preempt] [--namespace NS] [--ros-args -r FROM:=TO ...]
    actorbt goal TREE --args '{k: v}'      # run a served tree: live feedback, Ctrl-C cancels
    actorbt rcall ACTOR ARG... [k=v]       # call an actor of a running `actorbt serve`
    actorbt rshell                         # the same, interactively, on one warm node

``goal``, ``rcall`` and ``rshell`` are ROS clients of a running ``actorbt serve`` (there
is no ``ros2`` command from pip); ``--namespace NS`` names the serve's namespace. Exit
status: 0 succeeded; 1 failed, aborted or canceled; 2 refused (an invalid goal, a busy
tree), unknown tree or no server (the reason is printed); 130 interrupted with Ctrl-C
(the goal was cancelled).

``serve`` prints how its start-up goes (on stderr), then one line per goal on stdout:
a tree goal when it is accepted and when it ends (outcome, time, trace), a call of
``/actorbt/call`` when it ends, every refused goal with its reason, and each tree the
watched trees folder adds or withdraws.

Nothing here imports rclpy until a command runs.
"""

from __future__ import annotations

import argparse
import json
import os
import pprint
import signal
import sys
import threading
import time
from typing import TYPE_CHECKING, Callable

from bt_engine.clock import process_uptime
from .live_options import LiveOptions, add_live_options

if TYPE_CHECKING:
    import types

    from bt_engine.bus.messages import RosMessage
    from .command_app import CommandApp
    from .remote import RemoteGoal


def register(sub: argparse._SubParsersAction, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser(
        "serve",
        help="Serve the trees and actors as ROS 2 actions until Ctrl-C.",
        description="Serve every tree as its own ROS 2 action (/actorbt/tree/<name>) and any "
        "actor through /actorbt/call, until Ctrl-C. One line per goal tells what "
        "was asked and how it ended.",
    )
    common(p)
    p.add_argument(
        "--preempt",
        action="store_true",
        help="A new goal for a tree that is running cancels the running goal "
        "(default: the new goal is refused: aborted at once, BUSY).",
    )
    p.add_argument(
        "--record-dir",
        metavar="DIR",
        help="The folder where each tree goal's trace is written (default: .actorbt/goals beside actorbt.yaml).",
    )
    p.add_argument("--no-record", action="store_true", help="Do not write a trace of each tree goal.")
    p.add_argument(
        "--namespace",
        metavar="NS",
        help="Serve in this ROS namespace (robot1: /robot1/actorbt/call ...), so several robots share a ROS domain.",
    )
    p.add_argument(
        "--no-watch",
        action="store_true",
        help="Serve the trees loaded at start-up only (default: watch the trees "
        "folder; trees added get an action, removed ones are withdrawn).",
    )
    p.add_argument(
        "--ros-args",
        dest="ros_args",
        nargs=argparse.REMAINDER,
        metavar="ARG",
        help="Arguments of rclpy for the serve's node, last on the line (e.g. "
        "--ros-args -r __ns:=/robot1 -r /actorbt/tree/x:=/foo).",
    )
    add_live_options(p, trace=False)
    p.set_defaults(func=cmd_serve)

    p = sub.add_parser(
        "goal",
        help="Run a tree of a running `actorbt serve`: TREE --args '{yaml}'.",
        description="Run a tree of a running `actorbt serve` as a ROS 2 goal, printing its "
        "feedback as it comes; Ctrl-C cancels the goal. A tree the serve does not "
        "offer fails at once, with the close matches.",
    )
    p.add_argument(
        "tree", help="The tree's name, as in /actorbt/tree/<name> (dots or slashes for a tree in a subsystem)."
    )
    p.add_argument(
        "--args",
        dest="inputs",
        default="",
        metavar="YAML",
        help="The tree's inputs as a YAML mapping, e.g. '{category: can}'.",
    )
    p.add_argument(
        "--wait",
        type=float,
        default=10.0,
        metavar="S",
        help="Seconds to wait for a running `actorbt serve` before giving up (default 10).",
    )
    p.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="Cancel the goal after this many seconds (default: wait for its end).",
    )
    p.add_argument("--namespace", metavar="NS", help="The namespace of the `actorbt serve` (as its --namespace).")
    p.add_argument("-q", "--quiet", action="store_true", help="Print only the outcome, not each feedback line.")
    p.set_defaults(func=cmd_goal)

    p = sub.add_parser(
        "rcall",
        help="Call an actor of a running `actorbt serve`: ACTOR ARG... (Python literals, k=v).",
        description="Call one actor of a running `actorbt serve` over ROS 2 and print its "
        "result. Each rcall is a new process and node; for many calls, "
        "`actorbt rshell` keeps one.",
    )
    p.add_argument(
        "actor", help="The actor's name, as the serve resolves it (e.g. get_pose or robot.navigation.get_pose)."
    )
    p.add_argument("args", nargs="*", help="The actor's arguments: Python literals, and NAME=VALUE for keywords.")
    p.add_argument(
        "--wait",
        type=float,
        default=10.0,
        metavar="S",
        help="Seconds to wait for a running `actorbt serve` before giving up (default 10).",
    )
    p.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="Cancel the call after this many seconds (default: wait for its end).",
    )
    p.add_argument("--namespace", metavar="NS", help="The namespace of the `actorbt serve` (as its --namespace).")
    p.add_argument("--json", action="store_true", help="Print the result as JSON (default: as Python would print it).")
    p.set_defaults(func=cmd_rcall)

    p = sub.add_parser(
        "rshell",
        help="An interactive actor shell on a running `actorbt serve`.",
        description="Call actors of a running `actorbt serve` interactively, one call per "
        "line, with tab completion and `help NAME`. The shell keeps one ROS node, "
        "so each call after the first takes a round trip, not a start-up.",
    )
    p.add_argument(
        "--wait",
        type=float,
        default=10.0,
        metavar="S",
        help="Seconds to wait for a running `actorbt serve` before giving up (default 10).",
    )
    p.add_argument(
        "--timeout",
        type=float,
        metavar="S",
        help="Cancel each call after this many seconds (default: wait for its end).",
    )
    p.add_argument("--namespace", metavar="NS", help="The namespace of the `actorbt serve` (as its --namespace).")
    p.set_defaults(func=cmd_rshell)


def _progress(text: str) -> None:
    print(f"actorbt serve: {text}", file=sys.stderr, flush=True)


# -- serve -------------------------------------------------------------------------------
def cmd_serve(args: argparse.Namespace, app: CommandApp) -> int:
    from .server import serve

    previous = signal.getsignal(signal.SIGTERM)

    def on_term(signum: int, frame: types.FrameType | None) -> None:
        raise KeyboardInterrupt

    rt = server = session = None
    live = LiveOptions.of(args, app.cfg.robot)
    live.check()
    try:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, on_term)
        bus = getattr(args, "bus", None) or app.cfg.transport
        subsystems = ", ".join(app.cfg.subsystems) or "none"
        folder = app.cfg.trees_dir()
        trees = f" and the trees in {os.path.relpath(folder)}" if folder and folder.is_dir() else ""
        loading = f"loading subsystems {subsystems}{trees} ({bus} bus)..."
        spec = app.world_spec()
        world_name = spec["name"] if spec else None  # world_up is called only when there is one
        if spec:
            _progress(f"starting world {world_name} (seed {spec.get('seed', 0)})...")
        else:
            _progress(loading)

        def world_up(world: object) -> None:
            _progress(f"world {world_name} up at {process_uptime():.1f} s; {loading}")

        rt = app.runtime(clock=getattr(args, "clock", None) or "wall", world_first=True, world_setup=world_up)
        _progress(f"actors and trees loaded at {process_uptime():.1f} s; starting the ROS node...")
        record_dir = None
        if not getattr(args, "no_record", False):
            record_dir = getattr(args, "record_dir", None) or str(app.cfg.base / ".actorbt" / "goals")
        watch = folder if folder and folder.is_dir() and not getattr(args, "no_watch", False) else None
        try:
            server = serve(
                rt,
                preempt=bool(getattr(args, "preempt", False)),
                record_dir=record_dir,
                on_event=lambda line: print(line, flush=True),
                namespace=getattr(args, "namespace", None),
                ros_args=getattr(args, "ros_args", None),
                trees_folder=watch,
            )
        except ValueError as e:  # a bad namespace or --ros-args
            print(f"actorbt serve: error: {e}", file=sys.stderr, flush=True)
            return 2
        transport = "ros" if rt.bus.name == "ros" else "local"
        node = server.node.get_fully_qualified_name()
        print(
            f"actorbt serve: node {node} ({transport} bus, "
            f"{'preempting' if server.preempt else 'refusing'} a second goal per tree)",
            flush=True,
        )
        for name in server.actions + server.services:
            print(f"  {name}", flush=True)
        if watch is not None:
            print(f"actorbt serve: watching {os.path.relpath(watch)} for trees added or removed", flush=True)
        if record_dir:
            print(f"actorbt serve: recording tree goals in {record_dir}", flush=True)
        if live:
            from bt_engine.trees import tree_host
            from .live import LiveSession

            session = LiveSession(rt, tree_host(rt, create=True), live, out=sys.stdout)
            if live.bag:
                print(f"actorbt serve: recording a bag in {live.bag}", flush=True)
        print(f"actorbt serve: ready in {process_uptime():.1f} s (Ctrl-C stops)", flush=True)
        stop = threading.Event()
        while not stop.wait(3600):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        try:
            try:
                if session is not None:
                    session.close()
            finally:
                if server is not None:
                    server.close()
        finally:
            if rt is not None:
                app.close(rt)
            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGTERM, previous)
    print("actorbt serve: stopped", flush=True)
    return 0


# -- clients -----------------------------------------------------------------------------
def _print_feedback(fb: RosMessage) -> None:
    active = f"  {fb.active_node}" if fb.active_node else ""
    print(f"[tick {fb.tick_count:4d} {fb.elapsed:7.2f} s] {fb.status}{active}", flush=True)


def _follow(goal: RemoteGoal, timeout: float | None) -> int | None:
    """Wait for ``goal``; on Ctrl-C or timeout cancel it. Returns 130 when interrupted."""
    try:
        if not goal.wait(timeout):
            print(f"actorbt: no result within {timeout:g} s; canceling the goal", file=sys.stderr)
            goal.cancel()
            goal.wait(5.0)
    except KeyboardInterrupt:
        print("actorbt: canceling the goal", file=sys.stderr, flush=True)
        goal.cancel()
        try:
            goal.wait(5.0)
        except KeyboardInterrupt:
            pass
        print(f"actorbt: goal {goal.status}", file=sys.stderr)
        return 130
    return None


def _not_sent(err: BaseException | None, what: str = "goal") -> int | None:
    """Exit status 2, with the reason printed, for a goal that never ran (rejected, no
    server); None otherwise."""
    from .client import ActionGoalError, GoalRejectedError, ServerUnavailableError
    from .remote import GoalRefusedError, NoServeError

    if err is None or isinstance(err, ActionGoalError):
        return None
    if isinstance(err, GoalRefusedError):
        print(f"actorbt: {err.server} refused the {what} ({err.code}): {err.reason}", file=sys.stderr)
    elif isinstance(err, GoalRejectedError):
        print(f"actorbt: {err.server} rejected the {what}" + (f": {err.reason}" if err.reason else ""), file=sys.stderr)
    elif isinstance(err, ServerUnavailableError):
        print(f"actorbt: {NoServeError(err.seconds)}", file=sys.stderr)
    else:
        print(f"actorbt: error: {err}", file=sys.stderr)
    return 2


def cmd_goal(args: argparse.Namespace, app: CommandApp) -> int:
    from .remote import NoServeError, Remote, UnknownTreeError

    with Remote(wait=args.wait, namespace=args.namespace) as remote:
        try:
            remote.check_tree(args.tree)
        except (NoServeError, UnknownTreeError) as e:
            print(f"actorbt: {e}", file=sys.stderr)
            return 2
        goal = remote.tree_goal(args.tree, args.inputs or "", on_feedback=None if args.quiet else _print_feedback)
        rc = _follow(goal, args.timeout)
        if rc is not None:
            return rc
        if not args.quiet:
            time.sleep(0.05)  # the last feedback may arrive just after the result
        rc = _not_sent(goal.error)
        if rc is not None:
            return rc
        res = goal.result
        print(f"status: {res.status if res is not None else goal.status}")
        if res is not None and res.outputs_yaml:
            print("outputs:")
            for line in res.outputs_yaml.rstrip().splitlines():
                print(f"  {line}")
        return 0 if goal.status == "succeeded" and res is not None and res.success else 1


def cmd_rcall(args: argparse.Namespace, app: CommandApp) -> int:
    """``actorbt rcall ACTOR ARG...``: one call through ``/actorbt/call``; the result is
    printed (``--json``: as JSON)."""
    import yaml

    from bt_engine.literals import parse_args
    from .remote import Remote

    pos, kw = parse_args(list(args.args))
    with Remote(wait=args.wait, namespace=args.namespace) as remote:
        goal = remote.call_goal(args.actor, *pos, **kw)
        rc = _follow(goal, args.timeout)
        if rc is not None:
            return rc
        rc = _not_sent(goal.error, "call")
        if rc is not None:
            return rc
        res = goal.result
        if res is None or not res.success:
            detail = (res.error_msg if res is not None else "") or goal.status
            print(f"actorbt: {args.actor} {goal.status}: {detail}", file=sys.stderr)
            return 1
        value = yaml.safe_load(res.result_yaml) if res.result_yaml else None
        if value is not None:
            print(json.dumps(value, default=str) if args.json else pprint.pformat(value))
        return 0


def cmd_rshell(args: argparse.Namespace, app: CommandApp) -> int:
    from .remote import NoServeError, Remote
    from .shell import RemoteShell

    print("actorbt rshell: looking for a running `actorbt serve`...", file=sys.stderr, flush=True)
    with Remote(wait=args.wait, namespace=args.namespace) as remote:
        try:
            trees = [a for a in remote.wait_for_serve() if a.startswith(remote.prefix + "tree/")]
        except NoServeError as e:
            print(f"actorbt: {e}", file=sys.stderr)
            return 2
        print(
            f"actorbt rshell: connected in {process_uptime():.1f} s ({len(trees)} trees served)",
            file=sys.stderr,
            flush=True,
        )
        interactive = sys.stdin.isatty()
        shell = RemoteShell(
            remote, app.actors_with_trees, timeout=args.timeout, stdin=None if interactive else sys.stdin
        )
        shell.cmdloop()
    return 0
