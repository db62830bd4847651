"""The pybullet world: a TurtleBot3 Waffle Pi + OpenManipulator-X in a house, on the bus.

    from sim import SimWorld
    sim = SimWorld(rt, world="house", seed=0).start()    # physics timer + ROS topics
    ...
    sim.close()

Helpers for the CLI: write_map(world, seed, out_pgm), snapshot(world, seed, out_png, camera).
"""
from .description import WorldError, WorldSpec, list_worlds, load_world
from .simworld import SimWorld

__all__ = ["SimWorld", "start_world", "WorldError", "WorldSpec", "list_worlds", "load_world", "write_map", "snapshot"]


def write_map(world="house", seed=0, out_pgm="map.pgm", resolution=0.05):
    """Write map_server's PGM + YAML pair for a world; returns (pgm_path, yaml_path)."""
    from .gridmap import build_grid, write_pgm_yaml

    return write_pgm_yaml(build_grid(load_world(world, seed), resolution), out_pgm)


def snapshot(world="house", seed=0, out_png="world.png", camera=False, camera_size=(640, 480)):
    """Top view PNG of the world; with camera=True also <out>_camera.png (RGB | depth).
    Returns the list of files written."""
    from .topview import snapshot as _snapshot

    return _snapshot(world, seed, out_png, camera=camera, camera_size=camera_size)


def start_world(runtime, world="house", seed=0, gui=False):
    """Build ``world`` with ``seed`` and put it on ``runtime`` (what actorbt.yaml's
    ``simulator: sim:start_world`` names). Returns the started SimWorld."""
    return SimWorld(runtime, world=world, seed=seed, gui=gui).start()
