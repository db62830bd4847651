"""``actorbt serve``, ``actorbt goal`` and ``actorbt rcall``.

    actorbt serve [--ros] [--preempt]     # serve trees and actors until Ctrl-C
    actorbt goal TREE --args '{k: v}'     # run a served tree: live feedback, Ctrl-C cancels
    actorbt rcall ACTOR ARG... [k=v]      # call an actor of a running `actorbt serve`

``goal`` and ``rcall`` are ROS clients (there is no ``ros2`` command from pip). Exit
status: 0 succeeded; 1 failed, aborted or canceled; 2 rejected or no server (the
reason is printed); 130 interrupted with Ctrl-C (the goal was cancelled).

Nothing here imports rclpy until a command runs.
"""
from __future__ import annotations

import argparse
import json
import pprint
import signal
import sys
import threading
import time
from typing import Any, Callable


def register(sub: Any, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser("serve", help="serve trees and actors as ROS 2 actions until Ctrl-C "
                                     "(/actorbt/call, /actorbt/tree/<name>)")
    common(p)
    p.add_argument("--preempt", action="store_true",
                   help="a goal for a running tree preempts it (default: it is rejected)")
    p.add_argument("--record-dir", metavar="DIR",
                   help="where each tree goal's trace is written "
                        "(default: .actorbt/goals beside actorbt.yaml)")
    p.add_argument("--no-record", action="store_true", help="do not record goals")
    p.set_defaults(func=cmd_serve)

    p = sub.add_parser("goal", help="run a served tree over ROS: TREE --args '{yaml}'")
    p.add_argument("tree", help="tree name (as in /actorbt/tree/<name>)")
    p.add_argument("--args", dest="inputs", default="", metavar="YAML",
                   help="the tree's inputs as a YAML mapping, e.g. '{category: can}'")
    p.add_argument("--wait", type=float, default=10.0,
                   help="seconds to wait for the server (default 10)")
    p.add_argument("--timeout", type=float, help="cancel the goal after this many seconds")
    p.add_argument("-q", "--quiet", action="store_true", help="no feedback lines")
    p.set_defaults(func=cmd_goal)

    p = sub.add_parser("rcall", help="call an actor of a running `actorbt serve` over ROS: "
                                     "ACTOR ARG... (Python literals, k=v)")
    p.add_argument("actor")
    p.add_argument("args", nargs="*")
    p.add_argument("--wait", type=float, default=10.0,
                   help="seconds to wait for the server (default 10)")
    p.add_argument("--timeout", type=float, help="cancel the call after this many seconds")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=cmd_rcall)


# -- serve -------------------------------------------------------------------------------
def cmd_serve(args: argparse.Namespace, app: Any) -> int:
    from .server import serve
    rt = app.runtime(clock=getattr(args, "clock", None) or "wall")
    server = None
    previous = signal.getsignal(signal.SIGTERM)

    def on_term(signum: int, frame: Any) -> None:
        raise KeyboardInterrupt
    try:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGTERM, on_term)
        record_dir = None
        if not getattr(args, "no_record", False):
            record_dir = getattr(args, "record_dir", None) or str(app.cfg.base / ".actorbt" / "goals")
        server = serve(rt, preempt=bool(getattr(args, "preempt", False)), record_dir=record_dir)
        transport = "ros" if rt.bus.name == "ros" else "local"
        print(f"actorbt serve: node /actorbt ({transport} bus, "
              f"{'preempting' if server.preempt else 'rejecting'} a second goal per tree)",
              flush=True)
        for action in server.actions:
            print(f"  {action}", flush=True)
        if record_dir:
            print(f"actorbt serve: recording tree goals in {record_dir}", flush=True)
        print("actorbt serve: ready (Ctrl-C stops)", flush=True)
        stop = threading.Event()
        while not stop.wait(3600):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        try:
            if server is not None:
                server.close()
        finally:
            app.close(rt)
            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGTERM, previous)
    print("actorbt serve: stopped", flush=True)
    return 0


# -- clients -----------------------------------------------------------------------------
def _print_feedback(fb: Any) -> None:
    active = f"  {fb.active_node}" if fb.active_node else ""
    print(f"[tick {fb.tick_count:4d}] {fb.status}{active}", flush=True)


def _follow(goal: Any, timeout: float | None) -> int | None:
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


def cmd_goal(args: argparse.Namespace, app: Any) -> int:
    from .client import ActionGoalError, GoalRejectedError
    from .names import tree_action_name
    from .remote import Remote
    with Remote(wait=args.wait) as remote:
        goal = remote.tree_goal(args.tree, args.inputs or "",
                                on_feedback=None if args.quiet else _print_feedback)
        rc = _follow(goal, args.timeout)
        if rc is not None:
            return rc
        if not args.quiet:
            time.sleep(0.05)  # the last feedback may arrive just after the result
        err = goal.error
        if isinstance(err, GoalRejectedError):
            print(f"actorbt: {tree_action_name(args.tree)} rejected the goal"
                  + (f": {err.reason}" if err.reason else ""), file=sys.stderr)
            return 2
        if err is not None and not isinstance(err, ActionGoalError):
            print(f"actorbt: error: {err}", file=sys.stderr)
            return 2
        res = goal.result
        print(f"status: {res.status if res is not None else goal.status}")
        if res is not None and res.outputs_yaml:
            print("outputs:")
            for line in res.outputs_yaml.rstrip().splitlines():
                print(f"  {line}")
        return 0 if goal.status == "succeeded" and res is not None and res.success else 1


def cmd_rcall(args: argparse.Namespace, app: Any) -> int:
    """Also usable as ``actorbt call --ros`` (reads actor, args, timeout, json, wait)."""
    import yaml

    from ..literals import parse_args
    from .client import ActionGoalError, GoalRejectedError
    from .names import CALL_ACTION
    from .remote import Remote
    pos, kw = parse_args(list(args.args))
    with Remote(wait=getattr(args, "wait", None) or 10.0) as remote:
        goal = remote.call_goal(args.actor, *pos, **kw)
        rc = _follow(goal, getattr(args, "timeout", None))
        if rc is not None:
            return rc
        err = goal.error
        if isinstance(err, GoalRejectedError):
            print(f"actorbt: {CALL_ACTION} rejected the call"
                  + (f": {err.reason}" if err.reason else ""), file=sys.stderr)
            return 2
        if err is not None and not isinstance(err, ActionGoalError):
            print(f"actorbt: error: {err}", file=sys.stderr)
            return 2
        res = goal.result
        if res is None or not res.success:
            detail = (res.error if res is not None else "") or goal.status
            print(f"actorbt: {args.actor} {goal.status}: {detail}", file=sys.stderr)
            return 1
        value = yaml.safe_load(res.result_yaml) if res.result_yaml else None
        if value is not None:
            print(json.dumps(value, default=str) if getattr(args, "json", False)
                  else pprint.pformat(value))
        return 0
