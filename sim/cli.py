"""`actorbt sim ...`: worlds from the terminal (a plugin named in actorbt.yaml).

    actorbt sim map --world house --seed 3 --out house.pgm      # map_server PGM + YAML
    actorbt sim snapshot --world house --seed 3 --out world.png [--camera]
    actorbt sim worlds                                           # list the worlds
    actorbt sim run --world house [--seed N] [--ros] [--gui]     # serve the sim's topics
"""
from __future__ import annotations

import argparse
import signal
import time


def register(sub, common) -> None:
    p = sub.add_parser("sim", help="the simulated world: map, snapshot, worlds, run")
    simsub = p.add_subparsers(dest="sim_command", metavar="SIM_COMMAND")
    simsub.required = True

    m = simsub.add_parser("map", help="write the world's occupancy grid as map_server PGM + YAML")
    _world_args(m)
    m.add_argument("--out", default="map.pgm", help="PGM path (the YAML goes beside it)")
    m.add_argument("--resolution", type=float, default=0.05, help="cell size [m]")
    m.set_defaults(func=cmd_map)

    s = simsub.add_parser("snapshot", help="top view PNG (and a camera frame with --camera)")
    _world_args(s)
    s.add_argument("--out", default="world.png")
    s.add_argument("--camera", action="store_true", help="also save the robot's camera frame")
    s.set_defaults(func=cmd_snapshot)

    w = simsub.add_parser("worlds", help="list the worlds")
    w.set_defaults(func=cmd_worlds)

    r = simsub.add_parser("run", help="run the world alone, serving its topics until Ctrl-C")
    common(r)
    r.add_argument("--seconds", type=float, help="stop after this much sim time")
    r.set_defaults(func=cmd_run)


def _world_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--world", default="house")
    p.add_argument("--seed", type=int, default=0)


def cmd_map(args, app) -> int:
    from . import write_map
    for f in write_map(args.world, args.seed, args.out, resolution=args.resolution):
        print(f)
    return 0


def cmd_snapshot(args, app) -> int:
    from . import snapshot
    for f in snapshot(args.world, args.seed, args.out, camera=args.camera):
        print(f)
    return 0


def cmd_worlds(args, app) -> int:
    from . import list_worlds
    for name in list_worlds():
        print(name)
    return 0


def cmd_run(args, app) -> int:
    """The world alone on the wall clock, its topics on the bus (over DDS with --ros)."""
    if not app.world_spec():
        args.world = "house"
    rt = app.runtime(clock="wall")
    signal.signal(signal.SIGTERM, _interrupt)  # stop as cleanly on SIGTERM as on Ctrl-C
    try:
        print(f"world {app.world_spec()['name']} running on the {rt.bus.name} bus; Ctrl-C stops it",
              flush=True)
        t0 = time.monotonic()
        while args.seconds is None or time.monotonic() - t0 < args.seconds:
            time.sleep(0.2)
    except KeyboardInterrupt:
        pass
    finally:
        app.close(rt)
    return 0


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt
