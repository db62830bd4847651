"""`actorbt robot`: the robot side alone, as a real robot and Nav2 offer it (a plugin
named in actorbt.yaml).

    actorbt robot --world house [--seed N]            # the simulator + the navstack, over ROS 2
    actorbt --config actorbt.real.yaml run bt_search  # the missions, in another shell
    actorbt robot --no-navstack                        # for a real Nav2 + AMCL run against it
    actorbt robot --fault scan-drop=0.1 --fault arm-abort=2   # faults a real robot has
    actorbt robot --interfaces [--json]                # what it offers, then exit

One process runs the simulated robot (its drivers and ros2_control controllers) and the
navstack (AMCL's and Nav2's stand-in) on the wall clock, over DDS, on one node (its name
is printed when it is ready). The simulator gives the localiser the pose the robot stands
at on ``/initialpose``, as a user would (``--no-initial-pose``: nobody does). ``--truth FILE``
writes the world's ground truth (the robot's and objects' poses) to a JSON file every
second and at the end: for a referee, never for the robot's loop.

The navstack is named by its python path (``--navstack``), as actorbt.yaml names it: the
simulator does not import it.
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import importlib
import json
import os
import signal
import sys
import time
from typing import TYPE_CHECKING

from bt_engine.clock import process_uptime

from .cli import _world_args

if TYPE_CHECKING:
    from bt_engine import Runtime, SubSystem

    from .simworld import SimWorld

#: what the navstack is, as actorbt.yaml names it
NAVSTACK = "navstack:NavStack"
#: [s, wall] between two writes of --truth
TRUTH_PERIOD = 1.0


def register(sub, common) -> None:
    p = sub.add_parser(
        "robot",
        help="run the robot side alone: the simulated robot and the navstack over ROS 2",
        description="Run the robot side as a real TurtleBot3 + OpenManipulator-X with Nav2 and "
        "AMCL would offer it: the simulated robot's drivers and controllers, and the "
        "navstack (the Nav2/AMCL stand-in), over ROS 2 on the wall clock, until "
        "Ctrl-C. Run the missions in another process with `actorbt --config "
        "actorbt.real.yaml run TREE`.",
    )
    _world_args(p)
    p.add_argument(
        "--no-navstack",
        action="store_true",
        help="Leave the navstack out: run your own Nav2 and AMCL against the simulator.",
    )
    p.add_argument(
        "--navstack",
        default=NAVSTACK,
        metavar="MODULE:CLASS",
        help=f"The navstack's SubSystem class (default: {NAVSTACK}).",
    )
    p.add_argument(
        "--no-initial-pose",
        action="store_true",
        help="Do not tell the localiser where the robot starts (by default the "
        "simulator does, on /initialpose, as a user would with RViz).",
    )
    p.add_argument(
        "--fault",
        action="append",
        metavar="NAME=VALUE",
        help="Inject a fault a real robot has (repeatable): scan-drop=P, scan-delay=S, "
        "camera-drop=P, camera-delay=S, arm-abort=N[,M] (the arm controller "
        "aborts its Nth goal half way), restart=T (at T seconds the drivers and "
        "the navstack go down and come back restart-for=S seconds later, default "
        "3, with no state).",
    )
    p.add_argument(
        "--truth",
        metavar="FILE.json",
        help="Write the world's ground truth (robot, objects, place location) to this "
        "JSON file every second and at the end, for a referee.",
    )
    p.add_argument(
        "--seconds", type=float, metavar="S", help="Stop after this many seconds (default: run until Ctrl-C)."
    )
    p.add_argument(
        "--interfaces",
        action="store_true",
        help="Print the topics, actions and services the robot side offers (with the "
        "navstack unless --no-navstack), then exit.",
    )
    p.add_argument("--json", action="store_true", help="With --interfaces: as one JSON object.")
    p.add_argument(
        "--bus",
        choices=("ros", "local"),
        default="ros",
        help="The transport (default ros; local only makes sense with --interfaces).",
    )
    p.set_defaults(func=cmd_robot)


def _subsystems(args) -> dict[str, str]:
    return {} if args.no_navstack else {"navstack": args.navstack}


def cmd_robot(args, app) -> int:
    from .faults import parse_faults

    faults = parse_faults(args.fault)  # a bad --fault fails before anything starts
    if not app.world_spec():
        args.world = "house"
    if args.interfaces:
        return _print_interfaces(args, app)
    signal.signal(signal.SIGTERM, _interrupt)  # stop as cleanly on SIGTERM as on Ctrl-C
    spec = app.world_spec()
    say = functools.partial(print, flush=True)
    say(
        f"actorbt robot: starting world {spec['name']} (seed {spec.get('seed', 0)}) on the {args.bus} bus...",
        file=sys.stderr,
    )
    side = RobotSide(args, app, faults)
    try:
        side.start()
        navstack = "no navstack (run Nav2 and AMCL)" if args.no_navstack else "navstack"
        say(
            f"robot ready in {process_uptime():.1f} s: world {spec['name']} (seed {spec.get('seed', 0)}), "
            f"{navstack}, node {side.node_name}, faults: {faults.describe()}; Ctrl-C stops it"
        )
        t0 = next_truth = time.monotonic()
        while args.seconds is None or time.monotonic() - t0 < args.seconds:
            if args.truth and time.monotonic() >= next_truth:
                side.write_truth(args.truth)
                next_truth += TRUTH_PERIOD
            time.sleep(0.1)
    except KeyboardInterrupt:
        pass
    finally:
        if args.truth and side.sim is not None:
            side.write_truth(args.truth)
        for line in side.fault_report():
            say(line)
        side.close()
    return 0


class RobotSide:
    """The simulated robot and the navstack on one runtime (wall clock)."""

    def __init__(self, args, app, faults) -> None:
        self.args, self.faults = args, faults
        self.node_name = "(local bus)"
        cfg = dataclasses.replace(app.cfg, subsystems={}, trees=None)
        self.app = type(app)(argparse.Namespace(**{**vars(args), "clock": "wall"}), cfg)
        self.rt: Runtime | None = None
        self.sim: SimWorld | None = None
        self._navstack_cls: type[SubSystem] | None = None
        self.events: list[str] = []

    def start(self) -> None:
        from . import start_world

        self.rt = rt = self.app.runtime(clock="wall", with_world=False)
        node = getattr(rt.bus, "node", None)
        if node is not None:
            self.node_name = node.get_fully_qualified_name()
        spec = self.app.world_spec()
        extra = {"locations": spec["locations"]} if spec.get("locations") else {}
        self.sim = start_world(
            rt,
            spec["name"],
            seed=int(spec.get("seed", 0)),
            initial_pose=not self.args.no_initial_pose,
            faults=self.faults if self.faults.any() else None,
            **extra,
        )
        self._navstack_cls = None
        if not self.args.no_navstack:
            self._navstack_cls = _import(self.args.navstack)
            rt.run_on_hub(rt.add_subsystem, "navstack", self._navstack_cls)
        if self.faults.restart is not None:
            rt.run_on_hub(rt.call_later, self.faults.restart, self._go_down)

    # -- the restart fault ------------------------------------------------------------
    def _go_down(self) -> None:
        assert self.rt is not None and self.sim is not None  # scheduled by start(), which set both
        self.sim.drivers_down()
        if self._navstack_cls is not None:
            navstack = self.rt.root.remove_subsystem("navstack")
            close = getattr(navstack, "close", None)  # a SubSystem need not have one (--navstack)
            if close is not None:
                close()
        self._event(f"fault: the robot side went down at {self.rt.now():.1f} s")
        self.rt.call_later(self.faults.restart_for, self._come_up)

    def _come_up(self) -> None:
        assert self.rt is not None and self.sim is not None  # scheduled by _go_down()
        self.sim.drivers_up()
        if self._navstack_cls is not None:
            self.rt.add_subsystem("navstack", self._navstack_cls)
        self._event(f"fault: the robot side came back at {self.rt.now():.1f} s")

    def _event(self, text: str) -> None:
        self.events.append(text)
        print(text, flush=True)

    def fault_report(self) -> list[str]:
        """What the injected losses did: messages dropped and sent, per topic."""
        from .faults import FaultyPublisher

        topics = self.sim.topics if self.sim is not None else None
        pubs = [] if topics is None else [topics.pub_scan, topics.pub_rgb, topics.pub_depth, topics.pub_info]
        return [f"fault: {p.topic}: {p.dropped} dropped, {p.sent} sent" for p in pubs if isinstance(p, FaultyPublisher)]

    # -- the referee's view -------------------------------------------------------------
    def write_truth(self, path: str) -> None:
        """The ground truth, as JSON, written whole (a reader never sees half a file)."""
        sim, rt = self.sim, self.rt
        assert sim is not None and rt is not None  # written once start() has set both
        try:
            robot = [round(float(v), 4) for v in sim.robot_pose()]
            objects = {
                name: {"category": sim.object_category(name), "pose": [round(float(v), 4) for v in pose]}
                for name, pose in sim.object_poses().items()
            }
        except Exception as e:  # the runtime is closing: keep the last file
            print(f"actorbt robot: truth not written: {e}", file=sys.stderr)
            return
        place = sim.place_location
        truth = {
            "time": round(rt.now(), 3),
            "world": sim.spec.name,
            "seed": sim.seed,
            "robot": robot,
            "start": [float(v) for v in sim.spec.robot_start],
            "objects": objects,
            "place": None
            if place is None
            else {
                "x": place.x,
                "y": place.y,
                "size_x": place.sx,
                "size_y": place.sy,
                "height": place.sz,
                "yaw": place.yaw,
            },
        }
        tmp = f"{path}.tmp"
        with open(tmp, "w") as f:
            json.dump(truth, f, indent=1)
        os.replace(tmp, path)

    def close(self) -> None:
        if self.rt is not None:
            if self.sim is not None:
                self.app.world = self.sim
            self.app.close(self.rt)


def _print_interfaces(args, app) -> int:
    from .cli import print_interfaces, world_interfaces

    offered = world_interfaces(args, app, _subsystems(args))
    if args.json:
        print(json.dumps(offered, indent=2))
        return 0
    side = "the simulated robot" + ("" if args.no_navstack else " and the navstack (Nav2 + AMCL)")
    print_interfaces(
        offered, f"World {offered['world']} (seed {offered['seed']}): what {side} offer, as the bus shows it"
    )
    return 0


def _import(path: str):
    """``module:Class`` -> the class (the navstack is named, not imported, by sim)."""
    from bt_engine.errors import ActorbtError

    module, _, name = path.partition(":")
    try:
        return getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as e:
        raise ActorbtError(f"--navstack {path!r}: cannot import it: {e}") from None


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt
