"""``actorbt action list [-t]``: the robot's action servers, as ``ros2 action list`` shows
them (there is no ``ros2`` command from pip).

    actorbt action list [-t] [--json]    # names (and types) of every action
    ... --bus ros [--wait S]             # over ROS 2: a robot, or an
                                         # `actorbt sim run --bus ros` elsewhere

Where the actions are: as for ``actorbt topic`` (:mod:`bt_cli.topic`), on the local
bus this process builds the runtime actorbt.yaml names (subsystems and world, not the
trees) and lists the actions served on its bus; with ``--bus ros`` a node lists the
actions of the ROS graph after ``--wait`` seconds of discovery: like ``ros2 action list``,
those with a server or only a client anywhere.

Exit status: 0; 2 for a bad option; 130 on Ctrl-C. Nothing here imports ROS, the
simulator or the robot until the command runs.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import TYPE_CHECKING, Callable

from .topic import Bus, _run

if TYPE_CHECKING:
    from bt_engine.bus.transport import EndpointInfo
    from .app import App


def register(sub: argparse._SubParsersAction, common: Callable[[argparse.ArgumentParser], None]) -> None:
    p = sub.add_parser(
        "action",
        help="the robot's actions: list (like ros2 action)",
        description="Look at the robot's actions as `ros2 action` does. On the local bus they "
        "are the actions served by the runtime actorbt.yaml names (its subsystems "
        "and world, started here); with --bus ros, those of the ROS graph (a robot, "
        "or an `actorbt sim run --bus ros` in another process).",
    )
    asub = p.add_subparsers(dest="action_command", metavar="ACTION_COMMAND")
    asub.required = True

    q = asub.add_parser(
        "list",
        help="list the actions (with -t, their types)",
        description="List every action on the bus, one per line; with -t, each with its type in brackets.",
    )
    q.add_argument(
        "-t",
        "--show-types",
        action="store_true",
        help="Show each action's type after its name, as [package/action/Name].",
    )
    q.add_argument("--json", action="store_true", help="Print a JSON list of the actions: name and type.")
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


def actions(bus: Bus, wait: float) -> list[EndpointInfo]:
    """The bus's actions; over ROS after ``wait`` seconds of discovery (participants
    announce themselves over time, so a graph read at once is incomplete)."""
    if not bus.ros:
        return bus.rt.run_on_hub(bus.rt.bus.actions)
    time.sleep(max(0.0, wait))
    return bus.rt.bus.actions()


def cmd_list(args: argparse.Namespace, app: App) -> int:
    def body(bus: Bus) -> int:
        found = actions(bus, args.wait)
        if args.json:
            print(json.dumps([a._asdict() for a in found], indent=2))
            return 0
        for a in found:
            print(f"{a.name} [{a.type}]" if args.show_types else a.name)
        return 0

    return _run(args, app, body)
