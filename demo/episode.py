"""One episode of a mission in a fresh simulated world, with its trace, its outcome
checked against the simulator's truth, and pictures.

The episode plays the referee, never the robot (the simulator tells the localiser where
the robot starts, as a user would with RViz's "2D Pose Estimate"): it reads the simulator's
own state (``SimWorld.robot_pose()``, object poses) to score the outcome, draw the robot's
true path and measure the localisation's error (the robot's map -> base_footprint on /tf
against the true pose, every :data:`LOC_PERIOD` s).
"""

from __future__ import annotations

import argparse
import math
import pathlib
import sys
import time
from dataclasses import dataclass, field
from typing import Any, TextIO

from tf2_msgs.msg import TFMessage

import categories
from bt_engine import ActorError, Runtime
from bt_cli import App, Config, ConfigError, find_config, load_config
from bt_engine.trees import TraceRecorder, TreeObserver, tree_host
from planning.tf_buffer import TransformBuffer, TransformError, pose2d
from sim import SimWorld

from .first_failure import FirstFailure
from .grasp_probe import GraspProbe

#: the reference application's own actorbt.yaml, used when none is found from here
REPO_CONFIG = pathlib.Path(__file__).resolve().parents[1] / "actorbt.yaml"
#: [m] an object moved farther than this, that no pick went for, was pushed by the robot
PUSHED = 0.05
#: [s] between two samples of the localisation error, and of the true path
LOC_PERIOD, PATH_PERIOD = 0.5, 0.1


def without_map_server(setup: Any):
    """A world_setup that first turns the world's map server off, then runs ``setup``."""

    def run(world: SimWorld) -> None:
        world.serve_map = False
        if setup is not None:
            setup(world)

    return run


def episode_app(
    world: str, seed: int, app: App | None = None, config: Config | None = None, locations: str | None = None
) -> App:
    """The App an episode builds its runtime with: ``app``'s configuration (else
    ``config``, else the nearest actorbt.yaml, else the repository's), for ``world``
    and ``seed`` (and ``locations``, a locations YAML for a map-built world). So the
    subsystems, the trees folder and the simulator are the ones actorbt.yaml names, as
    for every other command."""
    if app is not None:
        return app.for_world(world, seed, locations)
    if config is None:
        config = load_config(find_config() or REPO_CONFIG)
    return App(argparse.Namespace(world=world, seed=seed, locations=locations), config)


@dataclass
class Episode:
    """What one run of a mission did. Times in seconds."""

    tree: str
    world: str
    seed: int
    category: str
    success: bool = False
    tree_status: str = ""
    failed_node: str = ""  # the first step that went wrong (tree:path), or where
    reason: str = ""  # the referee found it wrong ("ground truth"); why
    tree_failure: str = ""  # where and why the tree itself failed, at the end
    found: dict | None = None
    placed_object: str = ""
    sim_time: float = 0.0
    wall_time: float = 0.0
    trace: str = ""
    loc_rmse_m: float = float("nan")  # localisation error (position) over the episode
    loc_max_m: float = float("nan")
    grasp_tilt_deg: float = float("nan")  # largest tilt of the held object in the fingers
    pose: str = ""  # pose kind (upright, lying, tilted) the world gave
    support: str = ""  # the object placed, else the last pick's; what it stood on
    target: str = ""  # that object
    end_pose: str = ""  # its pose kind at the end of the episode
    end_support: str = ""  # and what it ended on: place location, floor, a surface
    pushed: list = field(default_factory=list)  # objects moved > PUSHED m that no pick went for
    objects: int | None = None  # a tidy-up: objects of a known category in the world,
    placed: int | None = None  # and how many ended where they belong
    result: Any = field(default=None, repr=False)  # what the tree (or actor) returned
    path: list = field(default_factory=list, repr=False)
    detections: list = field(default_factory=list, repr=False)
    loc_errors: list = field(default_factory=list, repr=False)  # (t, error [m])

    @property
    def realtime_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time else float("nan")


class TruthProbe:
    """The referee's view, sampled as the episode runs: the true path
    (``sim.robot_pose()``) every PATH_PERIOD, and the localisation error (the robot's
    map -> base_footprint on /tf against the true pose) every LOC_PERIOD. Sampled on each
    /tf message carrying the odometry, when /tf and the simulator are at the same instant."""

    def __init__(self, rt: Runtime, sim: SimWorld, ep: Episode) -> None:
        self.sim, self.ep, self.rt = sim, ep, rt
        self.buf = TransformBuffer()
        self._path_t = self._loc_t = -math.inf
        self._subs = [
            rt.bus.subscribe("/tf", TFMessage, self._on_tf, 100),
            rt.bus.subscribe("/tf_static", TFMessage, lambda m: self.buf.add_message(m, static=True), "latched"),
        ]

    def close(self) -> None:
        for s in self._subs:
            s.close()
        self._subs = []

    def _on_tf(self, msg: TFMessage) -> None:
        base = None
        for ts in msg.transforms:
            if ts.child_frame_id == "odom":
                self.buf.add_message(ts)  # the localiser's map -> odom
            elif ts.child_frame_id == "base_footprint":
                base = ts
        now = self.rt.now()
        if base is None or (now - self._path_t < PATH_PERIOD - 1e-9 and now - self._loc_t < LOC_PERIOD - 1e-9):
            return
        self.buf.add_message(base)  # only the newest is looked up
        if now - self._path_t >= PATH_PERIOD - 1e-9:
            self._path_t = now
            x, y, yaw = self.sim.robot_pose()
            self.ep.path.append((x, y))
        if now - self._loc_t >= LOC_PERIOD - 1e-9:
            try:
                ex, ey, _ = pose2d(self.buf.lookup("map", "base_footprint"))
            except TransformError:
                return  # not localised yet
            self._loc_t = now
            x, y, _ = self.sim.robot_pose()
            self.ep.loc_errors.append((now, math.hypot(ex - x, ey - y)))

    def summarise(self) -> None:
        errs = [e for _, e in self.ep.loc_errors]
        if errs:
            self.ep.loc_rmse_m = math.sqrt(sum(e * e for e in errs) / len(errs))
            self.ep.loc_max_m = max(errs)


class DemoProgress(TreeObserver):
    """Compact live progress: the active node of the top mission, and what was found where;
    and, when nothing was said for HEARTBEAT seconds of wall time, what is running now
    (the deepest running node of the innermost tree)."""

    #: [s] of wall time without a line after which the running node is told
    HEARTBEAT = 10.0

    def __init__(self, out: TextIO, rt: Runtime) -> None:
        self.out = out
        self.rt = rt
        self._last = ""
        self._said = time.monotonic()
        self._runs: dict[int, Any] = {}
        # a long actor (a patrol) ticks no tree: look once a simulated second
        self._beat = rt.call_every(1.0, self._heartbeat)

    def _say(self, text: str) -> None:
        self.out.write(f"[{self.rt.now():7.1f}s] {text}\n")
        self.out.flush()
        self._said = time.monotonic()

    def run_started(self, run) -> None:
        self._runs[run.id] = run

    def run_finished(self, run, status, outcome) -> None:
        self._runs.pop(run.id, None)

    def _heartbeat(self) -> None:
        if time.monotonic() - self._said < self.HEARTBEAT or not self._runs:
            return
        inner = max(self._runs.values(), key=lambda r: r.depth)
        tip = inner.tip_path()
        if tip is not None:
            self._say(f"  ... {inner.mission.name}: {tip}")

    def status_changed(self, run, path, old, new) -> None:
        if run.depth > 1 or new.name != "RUNNING":
            return
        label = f"{run.mission.name}: {path}"
        if path.count("/") <= 2 and label != self._last:
            self._last = label
            self._say(label)

    def actor_finished(self, run, leaf, txn) -> None:
        actor = leaf.node.actor
        if txn.state.value != "done":
            if txn.state.value == "failed":
                self._say(f"  {actor} failed: {txn.error}")
            return
        r = txn.result
        if actor == "watch" and isinstance(r, dict):
            self._say(f"  found a {r['category']} at ({r['x']:.2f}, {r['y']:.2f}), {r['distance']:.1f} m away")
        elif actor == "approach_object" and isinstance(r, dict):
            self._say(f"  close look: {r['category']} at ({r['x']:.3f}, {r['y']:.3f})")
        elif actor == "pick" and isinstance(r, dict):
            self._say(f"  holding the {r['category']} (fingers at {r['width'] * 1000:.0f} mm)")
        elif actor == "place_on" and isinstance(r, dict):
            self._say(f"  put it down at ({r['x']:.2f}, {r['y']:.2f})")
        elif actor == "survey" and isinstance(r, list):
            seen = ", ".join(f"{o['category']} at ({o['x']:.2f}, {o['y']:.2f})" for o in r)
            self._say(f"  survey found {len(r)} object{'s' * (len(r) != 1)}: {seen or 'none'}")
        elif actor == "tidy_one" and isinstance(r, dict):
            how = f"on the {r['place']}" if r["outcome"] == "placed" else f"failed: {r.get('reason', '')}"
            self._say(f"  the {r['category']} from ({r['x']:.2f}, {r['y']:.2f}): {how}")


class Sightings(TreeObserver):
    """Every object the robot reported seeing (``watch``, ``approach_object``, ``survey``)
    into ``detections``, for the top view: a failed run shows what it saw, too."""

    def __init__(self, detections: list) -> None:
        self.detections = detections

    def actor_finished(self, run, leaf, txn) -> None:
        if txn.state.value != "done" or leaf.node.actor not in ("watch", "approach_object", "survey"):
            return
        r = txn.result
        for d in r if isinstance(r, list) else [r]:
            if isinstance(d, dict) and {"category", "x", "y"} <= d.keys():
                self.detections.append(d)


def _on_surface(pose, place) -> bool:
    x, y, z = pose[:3]
    c, s = math.cos(place.yaw), math.sin(place.yaw)
    u, v = c * (x - place.x) + s * (y - place.y), -s * (x - place.x) + c * (y - place.y)
    return abs(u) <= place.sx / 2 and abs(v) <= place.sy / 2 and z > place.sz


def _surface(box) -> dict:
    return {"x": box.x, "y": box.y, "size_x": box.sx, "size_y": box.sy, "height": box.sz, "yaw": box.yaw}


def world_places(sim: SimWorld) -> dict:
    """The world's place surfaces by name: its place location and any other named places."""
    out = dict(getattr(sim.spec, "places", None) or {})
    if sim.place_location is not None:
        out.setdefault(sim.place_location.name, sim.place_location)
    return out


def _tidied(sim: SimWorld, places: dict, belongs: dict) -> tuple[int, int]:
    """(objects of a registered category in the world, how many of them stand on the place
    their category belongs to), by the simulator's truth; a category whose place this world
    lacks belongs to the default place, as the tidy-up mission decides."""
    total = done = 0
    for name in sim.object_names():
        cat = sim.object_category(name)
        if cat not in categories.names():
            continue  # a distractor
        total += 1
        where = belongs.get(cat)
        if where not in places:
            where = belongs.get("default")
        if where in places and _on_surface(sim.object_pose(name), places[where]):
            done += 1
    return total, done


def run_episode(
    tree: str = "bt_pick_place",
    world: str = "house",
    seed: int = 0,
    category: str = "any",
    out_dir: str | pathlib.Path | None = None,
    progress: TextIO | None = None,
    world_setup: Any = None,
    inputs: dict | None = None,
    observers: list | None = None,
    app: App | None = None,
    config: Config | None = None,
    locations: str | None = None,
    mapping: bool = False,
    live: Any = None,
) -> Episode:
    """Run ``tree`` once in a fresh ``world`` built from ``seed``.

    The runtime is built as every ``actorbt`` command builds it (see :func:`episode_app`):
    the subsystems, trees folder and simulator of actorbt.yaml; trees that do not load
    are skipped with a warning unless ``tree`` needs them.

    Success means the tree succeeded and, for a pick-and-place, an object of the category
    stands on the place location. ``world_setup(world)`` may change the world first and
    ``observers`` watch the tree runs (the fault tests use both); ``inputs`` are more tree
    inputs. With ``out_dir``, the trace and the top view are written there. ``locations``
    names places (a YAML file) for a world built from a map_server map. With ``mapping``
    the world has no map server: for trees that map it first (bt_map_then_fetch calls
    navstack's ``start_mapping``). ``live`` (a :class:`bt_ros.live_options.LiveOptions`)
    records a bag of the episode and serves a Foxglove view (``demo --bag --foxglove``).

    Raises:
        ConfigError: actorbt.yaml names no world to run in (or ``world`` is ``none``).
        SkippedTreeError: ``tree`` (or a tree it calls) did not load; the reason.
        UnknownActorError: no tree or actor ``tree``.
    """
    ep = Episode(tree=tree, world=world, seed=seed, category=category)
    out = pathlib.Path(out_dir) if out_dir else None
    wall0 = time.perf_counter()
    if mapping:
        world_setup = without_map_server(world_setup)
    app = episode_app(world, seed, app, config, locations)
    if app.world_spec() is None:
        raise ConfigError(f"an episode needs a simulated world, got --world {world}")
    rt = app.runtime(watchdog=None, world_first=True, world_setup=world_setup)
    sim: SimWorld = app.world
    try:
        host = tree_host(rt, create=True)
        assert host is not None
        if tree in host.library:
            host.library[tree]  # a skipped tree raises why, before anything runs
        if progress is not None:
            host.observers.append(DemoProgress(progress, rt))
        grasp = GraspProbe(sim, tuple(categories.names()))
        host.observers.append(grasp)
        first = FirstFailure()
        host.observers.append(first)
        host.observers.append(Sightings(ep.detections))
        host.observers.extend(observers or ())
        args = dict(inputs or {})
        params = rt.resolve(tree).signature.parameters
        if "category" in params:
            args.setdefault("category", category)
        pl = sim.place_location
        if "place" in params and pl is not None:  # this world's place location
            args.setdefault("place", _surface(pl))
        if "places" in params and world_places(sim):
            args.setdefault("places", {name: _surface(b) for name, b in world_places(sim).items()})
        if "locations" in params and sim.spec.search_locations:  # this world's, if it lists them
            args.setdefault("locations", [list(p) for p in sim.spec.search_locations])
        start = tuple(sim.spec.robot_start)  # the world's known start pose
        if "home" in params:
            args.setdefault("home", {"x": start[0], "y": start[1], "yaw": start[2]})
        probe = TruthProbe(rt, sim, ep)
        recorder = None
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
            ep.trace = str(out / "trace.jsonl")
            recorder = TraceRecorder(ep.trace, host, tree=tree, inputs=args, seed=seed)
        session = None
        if live:
            from bt_ros import LiveSession

            session = LiveSession(rt, host, live, tree=tree, inputs=args, seed=seed)
        before = {n: sim.object_pose(n) for n in sim.object_names()}
        sim0 = rt.now()
        try:
            result = rt.call(tree, **args)
            ep.tree_status = "SUCCESS"
            ep.result = result
            ep.found = (result or {}).get("found") if isinstance(result, dict) else None
        except ActorError as exc:
            cause = exc.__cause__
            ep.tree_status = "FAILURE"
            ep.tree_failure = str(cause if cause is not None else exc)
            ep.failed_node = getattr(cause, "path", "") or _failed_node(ep.tree_failure)
            ep.reason = ep.tree_failure
            if first.node:
                ep.failed_node, ep.reason = first.node, first.reason
        finally:
            ep.sim_time = rt.now() - sim0
            ep.grasp_tilt_deg = grasp.worst
            probe.close()
            probe.summarise()
            if recorder is not None:
                recorder.close()
            if session is not None:
                session.close()
        ep.success = ep.tree_status == "SUCCESS"
        if ep.success and sim.place_location is not None and tree in ("bt_pick_place", "bt_carry"):
            placed = [
                n
                for n in sim.object_names()
                if _on_surface(sim.object_pose(n), sim.place_location)
                and not _on_surface(before[n], sim.place_location)
            ]
            wanted = [n for n in placed if category in ("any", "mixed") or sim.object_category(n) == category]
            ep.placed_object = wanted[0] if wanted else ""
            if not wanted:
                ep.success = False
                ep.failed_node = "ground truth"
                ep.reason = "the tree succeeded but no object of the category is on the place location"
        ep.target = ep.placed_object or (grasp.picked or [""])[-1]
        ep.pose, ep.support = _start_pose(sim, ep.target)
        if ep.target:
            ep.end_pose, ep.end_support = _end_state(sim, ep.target)
        ep.pushed = sorted(
            n
            for n in sim.object_names()
            if n not in grasp.picked and math.dist(before[n][:2], sim.object_pose(n)[:2]) > PUSHED
        )
        if "belongs" in params:  # a tidy-up: every object where it belongs
            belongs = args.get("belongs", params["belongs"].default)
            ep.objects, ep.placed = _tidied(sim, world_places(sim), belongs)
            if ep.success and ep.placed < ep.objects:
                ep.success = False
                ep.failed_node = "ground truth"
                ep.reason = f"{ep.objects - ep.placed} of {ep.objects} objects are not where they belong"
        if out is not None:
            _draw(sim, ep, out / "top_view.png")
    finally:
        app.close(rt)
    ep.wall_time = time.perf_counter() - wall0
    return ep


def _start_pose(sim: SimWorld, name: str) -> tuple[str, str]:
    """(pose kind, support) the world gave object ``name``; ("", "") for no object."""
    for o in sim.spec.objects:
        if o.name == name:
            return o.pose_kind, o.support
    return "", ""


#: [deg] from the vertical: an object's axis within this is upright, beyond LYING lying
UPRIGHT, LYING = 15.0, 75.0


def _end_state(sim: SimWorld, name: str) -> tuple[str, str]:
    """(pose kind, support) of object ``name`` now: upright, tilted or lying; on the place
    location, the floor, or a surface that high."""
    pose = sim.object_pose(name)
    qx, qy = pose[3], pose[4]
    tilt = math.degrees(math.acos(max(-1.0, min(1.0, 1 - 2 * (qx * qx + qy * qy)))))
    kind = "upright" if tilt <= UPRIGHT else "lying" if tilt >= LYING else "tilted"
    if sim.place_location is not None and _on_surface(pose, sim.place_location):
        return kind, "the place location"
    bottom = sim.object_bottom(name)
    return kind, "the floor" if bottom < 0.02 else f"a surface {bottom:.2f} m high"


def _failed_node(reason: str) -> str:
    # TreeFailure messages start with "tree NAME failed at PATH: ..." in the trees layer
    marker = " at "
    if marker in reason:
        return reason.split(marker, 1)[1].split(":", 1)[0].strip()
    return ""


def _draw(sim: SimWorld, ep: Episode, png: pathlib.Path) -> None:
    from sim.topview import draw_top_view

    def overlay(ax) -> None:
        if ep.path:
            xs, ys = zip(*ep.path)
            ax.plot(xs, ys, "-", color=(0.1, 0.35, 0.8), lw=1.2, alpha=0.8, zorder=5, label="robot path")
            ax.plot(xs[0], ys[0], "o", color=(0.1, 0.35, 0.8), ms=6, zorder=6)
        labelled = set()
        for d in ep.detections:
            label = f"detected {d['category']}"
            ax.plot(
                d["x"], d["y"], "x", color="magenta", ms=10, mew=2, zorder=9, label=None if label in labelled else label
            )
            labelled.add(label)
        if ep.placed_object:
            x, y = sim.object_pose(ep.placed_object)[:2]
            ax.plot(x, y, "*", color="gold", mec="k", ms=16, zorder=9, label=f"placed {ep.placed_object}")
        ax.legend(loc="upper left", fontsize=8, framealpha=0.9)

    verdict = "success" if ep.success else f"FAILED at {ep.failed_node or '?'}"
    draw_top_view(
        sim, png, title=f"{ep.tree} in {ep.world} (seed {ep.seed}): {verdict}, {ep.sim_time:.0f} s sim", overlay=overlay
    )


def print_outcome(ep: Episode, out: TextIO = sys.stdout) -> None:
    if ep.success:
        where = f"; {ep.placed_object} is on the place location" if ep.placed_object else ""
        out.write(f"SUCCESS{where}\n")
    else:
        out.write(f"FAILURE at {ep.failed_node or '?'}: {ep.reason}\n")
        if ep.tree_failure and ep.tree_failure != ep.reason:
            out.write(f"  then the tree gave up: {ep.tree_failure}\n")
    out.write(f"sim time {ep.sim_time:.1f} s, wall time {ep.wall_time:.1f} s ({ep.realtime_factor:.1f}x real time)\n")
    if ep.target:
        what = "placed" if ep.placed_object else "the last pick went for"
        start = f"{ep.pose} on the {ep.support}" if ep.pose else "?"
        out.write(f"{what} {ep.target}: it stood {start}, it ended {ep.end_pose} on {ep.end_support}\n")
    if ep.pushed:
        out.write(f"objects the robot pushed more than {PUSHED * 100:.0f} cm: {', '.join(ep.pushed)}\n")
    if ep.objects is not None:
        out.write(f"objects where they belong: {ep.placed} of {ep.objects}\n")
    if ep.grasp_tilt_deg == ep.grasp_tilt_deg:
        out.write(f"held object's tilt in the hand: {ep.grasp_tilt_deg:.1f} deg at most\n")
    if ep.loc_errors:
        out.write(
            f"localisation error: {ep.loc_rmse_m * 100:.1f} cm rms, {ep.loc_max_m * 100:.1f} cm max "
            f"({len(ep.loc_errors)} samples)\n"
        )
