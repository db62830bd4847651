"""`actorbt sim ...`: worlds from the terminal (a plugin named in actorbt.yaml).

actorbt sim map --world house --seed 3 --out house.pgm      # map_server PGM + YAML
actorbt sim map --world house --height --out slice.pgm      # what the lidar sees
actorbt sim snapshot --world house --seed 3 --out world.png [--camera]
actorbt sim worlds                                           # list the worlds
actorbt sim run --world house [--seed N] [--bus ros] [--gui] # serve the sim's topics
actorbt sim interfaces --world house [--json]                # the topics and actions it offers
"""

from __future__ import annotations

import argparse
import dataclasses
import signal
import sys
import time

from bt_engine.clock import process_uptime


def register(sub, common) -> None:
    p = sub.add_parser(
        "sim",
        help="the simulated world: map, snapshot, worlds, run",
        description="The simulated world on its own: export its map, draw it, "
        "list the worlds, or run it for other processes.",
    )
    simsub = p.add_subparsers(dest="sim_command", metavar="SIM_COMMAND")
    simsub.required = True

    m = simsub.add_parser(
        "map",
        help="write the world's occupancy grid as map_server PGM + YAML",
        description="Write the world's occupancy grid as a map_server map: a PGM image and the YAML beside it.",
    )
    _world_args(m)
    m.add_argument(
        "--out",
        default="map.pgm",
        metavar="FILE.pgm",
        help="Where to write the PGM; the YAML goes beside it (default: map.pgm).",
    )
    m.add_argument(
        "--resolution", type=float, default=0.05, metavar="M", help="The cell size in metres (default: 0.05)."
    )
    m.add_argument(
        "--height",
        nargs="?",
        const="lidar",
        type=_height,
        metavar="H",
        help="Export a slice H metres above the floor, as a lidar there sees it: the "
        "boxes whose height covers H, and the objects that tall. '--height' alone: "
        "the lidar's height (the base_scan frame, 0.132 m), what a map built from "
        "the scan should show. Without it: every wall, piece of furniture and the "
        "place location, the map the robot plans on.",
    )
    m.set_defaults(func=cmd_map)

    s = simsub.add_parser(
        "snapshot",
        help="top view PNG (and a camera frame with --camera)",
        description="Draw the world from above as a PNG: walls, furniture, objects "
        "and the robot; with --camera, also the robot's camera frame.",
    )
    _world_args(s)
    s.add_argument(
        "--out", default="world.png", metavar="FILE.png", help="Where to write the top view (default: world.png)."
    )
    s.add_argument("--camera", action="store_true", help="Also save what the robot's camera sees, beside the top view.")
    s.set_defaults(func=cmd_snapshot)

    w = simsub.add_parser(
        "worlds",
        help="list the worlds",
        description="List the worlds that ship with actorbt (a world YAML file of "
        "your own works wherever a world name does).",
    )
    w.set_defaults(func=cmd_worlds)

    r = simsub.add_parser(
        "run",
        help="run the world alone, serving its topics until Ctrl-C",
        description="Run the simulated world alone on the wall clock, its robot's topics on "
        "the bus (with --bus ros, for an `actorbt serve --bus ros --world none` or "
        "a ROS 2 program in another process), until Ctrl-C. No actors or trees are "
        "loaded.",
    )
    common(r)
    r.add_argument(
        "--seconds", type=float, metavar="S", help="Stop after this many seconds (default: run until Ctrl-C)."
    )
    r.set_defaults(func=cmd_run)

    i = simsub.add_parser(
        "interfaces",
        help="the topics, actions and services the simulated robot offers",
        description="List what the simulated robot offers, with ROS type names: the topics it "
        "publishes and subscribes to, the actions and services it serves. The list "
        "is read from the bus of the world, started here for a moment, so it is "
        "what the world really offers; a real robot should offer the same.",
    )
    _world_args(i)
    i.add_argument(
        "--json",
        action="store_true",
        help="Print the interfaces as one JSON object: topics, actions and services, each with its name and type.",
    )
    i.set_defaults(func=cmd_interfaces)


def _world_args(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--world",
        default="house",
        metavar="NAME|FILE",
        help="The world: a world's name or its YAML file (default: house).",
    )
    p.add_argument(
        "--seed", type=int, default=0, metavar="N", help="The world's seed, which places the objects (default: 0)."
    )
    p.add_argument(
        "--locations",
        metavar="FILE.yaml",
        help="Named places (name: [x, y, theta] per line) for a world built from a "
        "map_server map: 'start', 'place' and the places to search.",
    )


def _height(text: str) -> float:
    """--height's value [m]: a number >= 0, or 'lidar'."""
    if text == "lidar":
        from .gridmap import lidar_height

        return lidar_height()
    try:
        h = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a height in metres or 'lidar', got {text!r}") from None
    if not h >= 0:
        raise argparse.ArgumentTypeError(f"expected a height >= 0 m, got {text}")
    return h


def cmd_map(args, app) -> int:
    from . import write_map

    height = _height(args.height) if isinstance(args.height, str) else args.height  # the const
    for f in write_map(
        args.world, args.seed, args.out, resolution=args.resolution, height=height, locations=args.locations
    ):
        print(f)
    return 0


def cmd_snapshot(args, app) -> int:
    from . import snapshot

    for f in snapshot(args.world, args.seed, args.out, camera=args.camera, locations=args.locations):
        print(f)
    return 0


def cmd_worlds(args, app) -> int:
    from . import list_worlds

    for name in list_worlds():
        print(name)
    return 0


def cmd_run(args, app) -> int:
    """The world alone on the wall clock, its topics on the bus (over DDS with --bus ros).

    Only the world is built: the subsystems and trees of actorbt.yaml are for the process
    that drives the robot (``actorbt serve``), and building them here took most of the
    start-up (the planning layer's imports)."""
    signal.signal(signal.SIGTERM, _interrupt)  # stop as cleanly on SIGTERM as on Ctrl-C
    if not app.world_spec():
        args.world = "house"
    spec = app.world_spec()
    bus = getattr(args, "bus", None) or app.cfg.transport
    print(
        f"actorbt sim run: starting world {spec['name']} (seed {spec.get('seed', 0)}) on the {bus} bus...",
        file=sys.stderr,
        flush=True,
    )
    world_only = type(app)(args, dataclasses.replace(app.cfg, subsystems={}, trees=None))
    rt = world_only.runtime(clock="wall")
    try:
        print(
            f"world {spec['name']} running on the {rt.bus.name} bus, ready in {process_uptime():.1f} s; "
            "Ctrl-C stops it",
            flush=True,
        )
        t0 = time.monotonic()
        while args.seconds is None or time.monotonic() - t0 < args.seconds:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        world_only.close(rt)
    return 0


def cmd_interfaces(args, app) -> int:
    """What the world offers, from its bus: the world is started alone (no subsystems, no
    trees) on the local bus and the virtual clock, listed, and closed."""
    import json

    offered = world_interfaces(args, app)
    if args.json:
        print(json.dumps(offered, indent=2))
        return 0
    print_interfaces(
        offered,
        f"World {offered['world']} (seed {offered['seed']}): what the simulated robot offers, as its bus shows it",
    )
    return 0


def print_interfaces(offered: dict, heading: str) -> None:
    """The topics, actions and services of :func:`world_interfaces` as a table."""
    print(heading)
    sections = [
        ("Topics it publishes", [t for t in offered["topics"] if "publish" in t["direction"]]),
        ("Topics it subscribes to", [t for t in offered["topics"] if "subscribe" in t["direction"]]),
        ("Actions it serves", offered["actions"]),
        ("Services it serves", offered["services"]),
    ]
    rows = [row for _, items in sections for row in items]
    width = max((len(r["name"]) for r in rows), default=0) + 2
    type_width = max((len(r["type"]) for r in rows), default=0) + 2
    for title, items in sections:
        print(f"\n{title}:" if items else f"\n{title}: none")
        for r in items:
            qos = r.get("qos", "")
            print(f"  {r['name']:<{width}}{r['type']:<{type_width if qos else 0}}{qos}".rstrip())


def world_interfaces(args, app, subsystems: dict[str, str] | None = None) -> dict:
    """``{"world", "seed", "topics": [{"name", "type", "direction", "qos"}], "actions":
    [{"name", "type"}], "services": [...]}`` of the world ``args`` names, read from the bus
    of that world started alone on the local bus (with ``subsystems``, name: python path,
    beside it: what ``actorbt robot`` runs). ``direction`` is the robot's: ``publishes``,
    ``subscribes`` or both. What the simulator publishes as the user (``/initialpose``)
    is not the robot's."""
    from bt_engine.errors import ActorbtError

    from .topics import USER_TOPICS

    if args.world == "none":
        raise ActorbtError("sim interfaces needs a world, e.g. --world house")
    only = argparse.Namespace(**{**vars(args), "bus": "local", "clock": "virtual", "gui": False})
    cfg = dataclasses.replace(
        app.cfg, subsystems=dict(subsystems or {}), trees=None, simulator=app.cfg.simulator or "sim:start_world"
    )
    world_only = type(app)(only, cfg)
    rt = world_only.runtime(clock="virtual", watchdog=None)
    try:
        bus = rt.bus
        topics, actions, services = rt.run_on_hub(lambda: (bus.topics(), bus.actions(), bus.services()))
    finally:
        world_only.close(rt)
    spec = world_only.world_spec()

    def direction(t) -> str:
        publishers = t.publishers - (t.name in USER_TOPICS)
        roles = (("publishes", publishers), ("subscribes", t.subscribers))
        return " and ".join(role for role, count in roles if count)

    rows = [{"name": t.name, "type": t.type, "direction": direction(t), "qos": t.qos} for t in topics]
    return {
        "world": spec["name"],
        "seed": int(spec.get("seed", 0)),
        "topics": [r for r in rows if r["direction"]],
        "actions": [{"name": a.name, "type": a.type} for a in actions],
        "services": [{"name": s.name, "type": s.type} for s in services],
    }


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt
