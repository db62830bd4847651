"""World descriptions: YAML in sim/worlds/, validated with file:line errors, objects placed
at random in free floor space from a seed (same seed -> same world).

Format (all lengths in metres, angles in radians)::

    name: house
    bounds: [xmin, ymin, xmax, ymax]       # extent of the map
    wall: {height: 0.5, thickness: 0.1}    # defaults for walls
    walls:                                 # centre lines [x0, y0, x1, y1]
      - [0, 0, 10, 0]
    rooms:                                 # named areas [xmin, ymin, xmax, ymax] for placement
      kitchen: [6, 0, 10, 4.5]
    furniture:                             # static boxes
      - {name: sofa, center: [1, 3], size: [1.8, 0.8, 0.45], yaw: 0, color: [r, g, b]}
    place_location: {name: pallet, center: [8, 7], size: [0.6, 0.4, 0.1], yaw: 0}
    robot: {start: [1, 1, 0]}
    search_locations: [[1.8, 2.0], [4.8, 1.6]]   # optional: where a search looks around
    placement: {clearance: 0.3, tries: 500}
    objects:
      - {category: can, count: 1, room: kitchen}   # random, seeded
      - {category: box, name: crate, pose: [2, 1, 0]}   # fixed pose [x, y, yaw]
      - {category: others}          # one of every registered category not listed above
                                    # (in a random room, or the given one)

Worlds with varied poses and looks (house_hard) add::

    furniture:
      - {name: bench, center: [5, 3], size: [1.0, 0.4, 0.25], support: true}   # a low table
    poses: {upright: 0.5, lying: 0.3, tilted: 0.2,   # the mix of pose kinds (weights)
            tilt_deg: [15, 35],       # leaning against a wall or furniture (steeper if needed)
            on_tables: 0.4,           # chance an upright object stands on a table in its room
            settle_steps: 300}        # physics steps at world creation, before the robot
    objects:
      - {category: can, room: living, pose_kind: lying, support: floor}   # both optional
    distractors: {count: [4, 7], kinds: [mug, duck, tin], on_tables: 0.3}  # sim.objects.DECOYS
    appearance:                       # each: true (defaults), false, or a mapping
      labels: true                    # the categories' Labels, textured
      lighting: {elevation: [25, 80], brightness: [0.75, 1.15], tint: 0.08, ambient: [0, 0.06]}
      color_jitter: {hue: 0.015, saturation: 0.1, value: 0.12}
      depth_noise: {a: 0.0012, b: 0.0019, z0: 0.4, dropout: 0.7, grazing_deg: 80, speckle: 0.001}
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml

import categories as registry

from .appearance import Appearance, ColorJitter, DepthNoise, Lighting, LightingRange
from .gridmap import is_map_yaml
from .map_world import build_map_world
from .marked_yaml import compose_yaml
from .objects import CATEGORIES, DECOYS
from .textures import jitter_rgba
from .varied import Placer
from .world_spec import POSE_KINDS, Box, Distractors, PlacedObject, PoseMix, WorldError, WorldSpec

WORLDS_DIR = Path(__file__).resolve().parent / "worlds"
ROBOT_RADIUS = 0.26  # circle around base_footprint that covers the Waffle Pi chassis
DOOR_CLEARANCE = 0.6  # random objects keep this far from wall ends (doorways, corners)
OTHERS = "others"  # an objects entry for one of every registered category not listed


def _rgba(ctx, node, default):
    if node is None:
        return default
    items = ctx.seq(node, "color")
    if len(items) not in (3, 4):
        raise ctx.err(node, "color must be [r, g, b] or [r, g, b, a] in 0..1")
    vals = [ctx.num(i, "color", nonneg=True) for i in items]
    return tuple(vals) + ((1.0,) if len(vals) == 3 else ())


def _box(ctx, node, what, default_rgba, default_name, tables=False):
    m = ctx.mapping(node, what)
    ctx.keys(m, {"name", "center", "size", "yaw", "color"} | ({"support"} if tables else set()), what)
    for req in ("center", "size"):
        if req not in m:
            raise ctx.err(node, f"{what}: missing '{req}'")
    name = ctx.str_(m["name"][1], f"{what}.name") if "name" in m else default_name
    cx, cy = ctx.vec(m["center"][1], 2, f"{what}.center")
    sx, sy, sz = ctx.vec(m["size"][1], 3, f"{what}.size", positive=True)
    yaw = ctx.num(m["yaw"][1], f"{what}.yaw") if "yaw" in m else 0.0
    support = _bool(ctx, m["support"][1], f"{what}.support") if "support" in m else False
    return Box(name, cx, cy, sx, sy, sz, yaw, _rgba(ctx, m.get("color", (None, None))[1], default_rgba), support)


def _bool(ctx, node, what):
    if isinstance(node, yaml.ScalarNode) and node.value.lower() in ("true", "false", "yes", "no", "on", "off"):
        return node.value.lower() in ("true", "yes", "on")
    raise ctx.err(node, f"{what} must be true or false, got {getattr(node, 'value', 'a ' + type(node).__name__)!r}")


def _range(ctx, node, what, lo=None, hi=None):
    """[low, high] of two numbers (within lo..hi when given)."""
    a, b = ctx.vec(node, 2, what)
    if a > b:
        raise ctx.err(node, f"{what} must be [low, high] with low <= high, got [{a:g}, {b:g}]")
    for v in (a, b):
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            raise ctx.err(node, f"{what} must be within {lo:g}..{hi:g}, got [{a:g}, {b:g}]")
    return (a, b)


def _switch(ctx, node, what, cls, fields):
    """``true`` (cls's defaults), ``false`` (None) or a mapping of some of ``fields``
    (name -> 'num', 'nonneg', 'fraction', 'range', 'frange'), given over cls's defaults."""
    if isinstance(node, yaml.ScalarNode):
        return cls() if _bool(ctx, node, what) else None
    m = ctx.mapping(node, what)
    ctx.keys(m, set(fields), what)
    kw = {}
    for key, (_, vnode) in m.items():
        kind, w = fields[key], f"{what}.{key}"
        if kind == "range":
            kw[key] = _range(ctx, vnode, w)
        elif kind == "frange":
            kw[key] = _range(ctx, vnode, w, 0.0, 1.0)
        elif kind == "fraction":
            v = ctx.num(vnode, w, nonneg=True)
            if v > 1:
                raise ctx.err(vnode, f"{w} must be a fraction in 0..1, got {v:g}")
            kw[key] = v
        else:
            kw[key] = ctx.num(vnode, w, nonneg=kind == "nonneg")
    return cls(**kw)


def _appearance(ctx, node) -> Appearance:
    m = ctx.mapping(node, "appearance")
    ctx.keys(m, {"labels", "lighting", "color_jitter", "depth_noise"}, "appearance")
    kw = {}
    if "labels" in m:
        kw["labels"] = _bool(ctx, m["labels"][1], "appearance.labels")
    if "lighting" in m:
        kw["lighting"] = _switch(
            ctx,
            m["lighting"][1],
            "appearance.lighting",
            LightingRange,
            {"elevation": "range", "brightness": "range", "tint": "fraction", "ambient": "frange"},
        )
        el = kw["lighting"].elevation if kw["lighting"] else (0, 90)
        if not (0 < el[0] and el[1] <= 90):
            raise ctx.err(m["lighting"][1], f"appearance.lighting.elevation must be within 0..90 deg, got {list(el)}")
    if "color_jitter" in m:
        kw["color_jitter"] = _switch(
            ctx,
            m["color_jitter"][1],
            "appearance.color_jitter",
            ColorJitter,
            {"hue": "fraction", "saturation": "fraction", "value": "fraction"},
        )
    if "depth_noise" in m:
        kw["depth_noise"] = _switch(
            ctx,
            m["depth_noise"][1],
            "appearance.depth_noise",
            DepthNoise,
            {
                "a": "nonneg",
                "b": "nonneg",
                "z0": "nonneg",
                "dropout": "fraction",
                "grazing_deg": "nonneg",
                "speckle": "fraction",
            },
        )
    return Appearance(**kw)


def _poses(ctx, node) -> PoseMix:
    m = ctx.mapping(node, "poses")
    ctx.keys(m, set(POSE_KINDS) | {"tilt_deg", "on_tables", "settle_steps"}, "poses")
    defaults = PoseMix()
    weights = dict(defaults.weights) if not set(POSE_KINDS) & set(m) else {}
    for kind in POSE_KINDS:
        if kind in m:
            weights[kind] = ctx.num(m[kind][1], f"poses.{kind}", nonneg=True)
    if sum(weights.values()) <= 0:
        raise ctx.err(node, f"poses: the weights of {', '.join(POSE_KINDS)} must not all be 0")
    tilt_deg, on_tables, settle_steps = defaults.tilt_deg, defaults.on_tables, defaults.settle_steps
    if "tilt_deg" in m:
        tilt_deg = _range(ctx, m["tilt_deg"][1], "poses.tilt_deg", 1.0, 55.0)
    if "on_tables" in m:
        v = ctx.num(m["on_tables"][1], "poses.on_tables", nonneg=True)
        if v > 1:
            raise ctx.err(m["on_tables"][1], f"poses.on_tables must be a fraction in 0..1, got {v:g}")
        on_tables = v
    if "settle_steps" in m:
        settle_steps = ctx.int_(m["settle_steps"][1], "poses.settle_steps", minimum=0)
    return PoseMix(
        weights=tuple((k, weights.get(k, 0.0)) for k in POSE_KINDS),
        tilt_deg=tilt_deg,
        on_tables=on_tables,
        settle_steps=settle_steps,
    )


def _distractors(ctx, node) -> Distractors:
    m = ctx.mapping(node, "distractors")
    ctx.keys(m, {"count", "kinds", "on_tables"}, "distractors")
    defaults = Distractors()
    count, kinds, on_tables = defaults.count, defaults.kinds, defaults.on_tables
    if "count" in m:
        cnode = m["count"][1]
        if isinstance(cnode, yaml.SequenceNode):
            lo, hi = _range(ctx, cnode, "distractors.count", 0)
            if lo != int(lo) or hi != int(hi):
                raise ctx.err(cnode, f"distractors.count must be whole numbers, got [{lo:g}, {hi:g}]")
            count = (int(lo), int(hi))
        else:
            n = ctx.int_(cnode, "distractors.count", minimum=0)
            count = (n, n)
    if "kinds" in m:
        named: list[str] = []
        for kn in ctx.seq(m["kinds"][1], "distractors.kinds"):
            k = ctx.str_(kn, "distractors.kinds")
            if k not in DECOYS:
                raise ctx.err(kn, f"distractors.kinds: unknown distractor '{k}' (one of: {', '.join(DECOYS)})")
            named.append(k)
        if not named:
            raise ctx.err(
                m["kinds"][1], f"distractors.kinds must name at least one distractor (one of: {', '.join(DECOYS)})"
            )
        kinds = tuple(named)
    if "on_tables" in m:
        v = ctx.num(m["on_tables"][1], "distractors.on_tables", nonneg=True)
        if v > 1:
            raise ctx.err(m["on_tables"][1], f"distractors.on_tables must be a fraction in 0..1, got {v:g}")
        on_tables = v
    return Distractors(count=count, kinds=kinds, on_tables=on_tables)


WALL_RGBA = (0.82, 0.80, 0.74, 1.0)
FURNITURE_RGBA = (0.55, 0.42, 0.30, 1.0)
PLACE_RGBA = (0.76, 0.60, 0.35, 1.0)


def parse_world(text: str, path: str = "<string>", seed: int = 0) -> WorldSpec:
    """Parse and validate a world description, then place its objects from ``seed``."""
    root, ctx = compose_yaml(text, path, "empty world description")
    top = ctx.mapping(root, "world")
    ctx.keys(
        top,
        {
            "name",
            "bounds",
            "wall",
            "walls",
            "rooms",
            "furniture",
            "place_location",
            "robot",
            "objects",
            "placement",
            "description",
            "search_locations",
            "poses",
            "appearance",
            "distractors",
        },
        "world",
    )
    if "bounds" not in top:
        raise ctx.err(root, "world: missing 'bounds' [xmin, ymin, xmax, ymax]")
    name = ctx.str_(top["name"][1], "name") if "name" in top else Path(path).stem
    bnode = top["bounds"][1]
    bounds = ctx.vec(bnode, 4, "bounds")
    if bounds[2] <= bounds[0] or bounds[3] <= bounds[1]:
        raise ctx.err(bnode, "bounds: need xmin < xmax and ymin < ymax")

    wall_h, wall_t = 0.5, 0.1
    if "wall" in top:
        wm = ctx.mapping(top["wall"][1], "wall")
        ctx.keys(wm, {"height", "thickness"}, "wall")
        if "height" in wm:
            wall_h = ctx.num(wm["height"][1], "wall.height", positive=True)
        if "thickness" in wm:
            wall_t = ctx.num(wm["thickness"][1], "wall.thickness", positive=True)

    spec = WorldSpec(name=name, source=path, bounds=bounds, seed=seed)
    for i, wn in enumerate(ctx.seq(top["walls"][1], "walls") if "walls" in top else []):
        x0, y0, x1, y1 = ctx.vec(wn, 4, f"walls[{i}]")
        length = math.hypot(x1 - x0, y1 - y0)
        if length <= 0:
            raise ctx.err(wn, f"walls[{i}]: zero-length wall")
        # extend by half a thickness at both ends so corners close
        spec.walls.append(
            Box(
                f"wall_{i}",
                (x0 + x1) / 2,
                (y0 + y1) / 2,
                length + wall_t,
                wall_t,
                wall_h,
                math.atan2(y1 - y0, x1 - x0),
                WALL_RGBA,
            )
        )

    if "rooms" in top:
        for rname, (knode, rnode) in ctx.mapping(top["rooms"][1], "rooms").items():
            r = ctx.vec(rnode, 4, f"rooms.{rname}")
            if r[2] <= r[0] or r[3] <= r[1]:
                raise ctx.err(rnode, f"rooms.{rname}: need xmin < xmax and ymin < ymax")
            spec.rooms[rname] = r

    for i, fn in enumerate(ctx.seq(top["furniture"][1], "furniture") if "furniture" in top else []):
        spec.furniture.append(_box(ctx, fn, f"furniture[{i}]", FURNITURE_RGBA, f"furniture_{i}", tables=True))
    names = [f.name for f in spec.furniture]
    for i, fn in enumerate(ctx.seq(top["furniture"][1], "furniture") if "furniture" in top else []):
        if spec.furniture[i].support and names.count(names[i]) > 1:
            raise ctx.err(
                fn, f"furniture[{i}]: a table (support: true) needs a name of its own; '{names[i]}' is taken twice"
            )

    if "appearance" in top:
        spec.appearance = _appearance(ctx, top["appearance"][1])
        if spec.appearance.lighting is not None:
            spec.lighting = Lighting.draw(np.random.default_rng([seed, 41]), spec.appearance.lighting)
    if "poses" in top:
        spec.poses = _poses(ctx, top["poses"][1])
    distractors = _distractors(ctx, top["distractors"][1]) if "distractors" in top else None
    if distractors is not None and spec.poses is None:
        raise ctx.err(
            top["distractors"][0],
            "distractors: needs a 'poses' block in the world (distractors are placed as objects with varied poses are)",
        )
    tables = [f.name for f in spec.furniture if f.support]

    if "place_location" in top:
        spec.place = _box(ctx, top["place_location"][1], "place_location", PLACE_RGBA, "place_location")

    if "robot" in top:
        rm = ctx.mapping(top["robot"][1], "robot")
        ctx.keys(rm, {"start"}, "robot")
        if "start" in rm:
            spec.robot_start = ctx.vec(rm["start"][1], 3, "robot.start")

    for i, ln in enumerate(
        ctx.seq(top["search_locations"][1], "search_locations") if "search_locations" in top else []
    ):
        x, y = ctx.vec(ln, 2, f"search_locations[{i}]")
        if not (bounds[0] <= x <= bounds[2] and bounds[1] <= y <= bounds[3]):
            raise ctx.err(ln, f"search_locations[{i}]: ({x:g}, {y:g}) is outside the bounds {list(bounds)}")
        spec.search_locations.append((x, y))

    clearance, tries = 0.30, 500
    if "placement" in top:
        pm = ctx.mapping(top["placement"][1], "placement")
        ctx.keys(pm, {"clearance", "tries"}, "placement")
        if "clearance" in pm:
            clearance = ctx.num(pm["clearance"][1], "placement.clearance", nonneg=True)
        if "tries" in pm:
            tries = ctx.int_(pm["tries"][1], "placement.tries", minimum=1)

    # robot start must be in free space
    sx, sy, _ = spec.robot_start
    for ob in spec.obstacles:
        if ob.distance(sx, sy) < ROBOT_RADIUS:
            raise ctx.err(top["robot"][1] if "robot" in top else root, f"robot.start ({sx}, {sy}) overlaps '{ob.name}'")

    entries = []  # (node, category, name, room, pose or None)
    wanted = {}  # name -> (pose kind, support) asked for (None: drawn)
    others = []  # (node, count, room) of "every category not listed" entries
    counters: dict[str, int] = {}
    for i, on in enumerate(ctx.seq(top["objects"][1], "objects") if "objects" in top else []):
        what = f"objects[{i}]"
        om = ctx.mapping(on, what)
        ctx.keys(om, {"category", "count", "room", "name", "pose", "pose_kind", "support"}, what)
        if "category" not in om:
            raise ctx.err(on, f"{what}: missing 'category' (one of: {', '.join(CATEGORIES)})")
        cnode = om["category"][1]
        cat = ctx.str_(cnode, f"{what}.category")
        if cat not in CATEGORIES and cat != OTHERS:
            raise ctx.err(
                cnode,
                f"{what}: unknown category '{cat}' (one of: {', '.join(CATEGORIES)}; "
                f"or {OTHERS}: every category not listed)",
            )
        count = ctx.int_(om["count"][1], f"{what}.count", minimum=1) if "count" in om else 1
        room = None
        if "room" in om:
            rnode = om["room"][1]
            room = ctx.str_(rnode, f"{what}.room")
            if room not in spec.rooms:
                raise ctx.err(rnode, f"{what}: unknown room '{room}' (rooms: {', '.join(spec.rooms) or 'none'})")
        pose = ctx.vec(om["pose"][1], 3, f"{what}.pose") if "pose" in om else None
        base = ctx.str_(om["name"][1], f"{what}.name") if "name" in om else None
        kind = sup = None
        for key in ("pose_kind", "support"):
            if key in om and spec.poses is None:
                raise ctx.err(om[key][0], f"{what}.{key}: needs a 'poses' block in the world")
        if "pose_kind" in om:
            knode = om["pose_kind"][1]
            kind = ctx.str_(knode, f"{what}.pose_kind")
            if kind not in POSE_KINDS:
                raise ctx.err(knode, f"{what}.pose_kind: expected one of {', '.join(POSE_KINDS)}, got '{kind}'")
        if "support" in om:
            snode = om["support"][1]
            sup = ctx.str_(snode, f"{what}.support")
            if sup != "floor" and sup not in tables:
                raise ctx.err(
                    snode,
                    f"{what}.support: expected 'floor' or a table (furniture with "
                    f"'support: true': {', '.join(tables) or 'none'}), got '{sup}'",
                )
            if sup != "floor" and kind not in (None, "upright"):
                raise ctx.err(
                    snode, f"{what}: objects on a table stand upright (pose_kind '{kind}' needs support: floor)"
                )
            if sup != "floor" and room is not None:
                x0, y0, x1, y1 = spec.rooms[room]
                t = next(f for f in spec.furniture if f.name == sup)
                if not (x0 <= t.x <= x1 and y0 <= t.y <= y1):
                    raise ctx.err(snode, f"{what}: table '{sup}' is not in room '{room}'")
        if cat == OTHERS:
            if pose is not None or base is not None:
                raise ctx.err(on, f"{what}: '{OTHERS}' stands for several categories: no 'pose' or 'name'")
            others.append((on, count, room, kind, sup))
            continue
        if pose is not None and count != 1:
            raise ctx.err(on, f"{what}: 'pose' fixes one object; drop 'count'")
        for _ in range(count):
            if base is not None and count == 1:
                oname = base
            else:
                stem = base or cat
                counters[stem] = counters.get(stem, 0) + 1
                oname = f"{stem}_{counters[stem]}"
            entries.append((on, cat, oname, room, pose))
            wanted[oname] = (kind, sup)
    listed = {e[1] for e in entries}
    room_rng = np.random.default_rng([seed, 7])  # apart from the placement stream
    for on, count, room, kind, sup in others:
        for cat in registry.names():
            if cat in listed:
                continue
            for _ in range(count):
                counters[cat] = counters.get(cat, 0) + 1
                where = room or (str(room_rng.choice(sorted(spec.rooms))) if spec.rooms else None)
                if sup not in (None, "floor") and room is None:
                    t = next(f for f in spec.furniture if f.name == sup)
                    where = spec.room_of(t.x, t.y)
                entries.append((on, cat, f"{cat}_{counters[cat]}", where, None))
                wanted[f"{cat}_{counters[cat]}"] = (kind, sup)
    names = [e[2] for e in entries]
    for e in entries:
        if names.count(e[2]) > 1:
            raise ctx.err(e[0], f"duplicate object name '{e[2]}'")

    if spec.poses is None:
        _place_objects(ctx, spec, entries, seed, clearance, tries)
    else:
        _place_varied(ctx, spec, entries, wanted, seed, clearance, tries, distractors)
    return spec


def _place_varied(ctx, spec, entries, wanted, seed, clearance, tries, distractors):
    """Placement in a world with ``poses``: see sim/varied.py."""
    placer = Placer(spec, clearance, tries, spec.poses, seed, ROBOT_RADIUS, DOOR_CLEARANCE)
    out = {}
    for node, cat, name, room, pose in entries:  # fixed poses first: upright, on the floor
        if pose is None:
            continue
        r = CATEGORIES[cat].radius
        if not placer.floor_free(pose[0], pose[1], r, 0.0, doorways=False):
            raise ctx.err(
                node,
                f"object '{name}': pose ({pose[0]}, {pose[1]}) collides with a wall, "
                f"furniture, the robot start or another object",
            )
        placer.placed.append((pose[0], pose[1], r))
        out[name] = PlacedObject(name, cat, pose[0], pose[1], pose[2])
    for node, cat, name, room, pose in entries:
        if pose is not None:
            continue
        kind, sup = wanted.get(name, (None, None))
        got = placer.place(name, cat, room, kind, sup)
        if got is None:
            where = f"room '{room}'" if room else "the world"
            how = f"{kind or 'any'} pose on {sup or 'the floor or a table'}"
            raise ctx.err(
                node,
                f"cannot place object '{name}' ({cat}) in {where} ({how}) after {tries} "
                f"tries: no free spot {clearance} m clear of walls, furniture, the robot "
                f"start and the objects already placed, with room for the robot to reach "
                f"it; lower 'count' or 'placement.clearance', or enlarge the area",
            )
        out[name] = got
    objects = [out[e[2]] for e in entries]
    if spec.appearance.color_jitter is not None:
        j, rng = spec.appearance.color_jitter, np.random.default_rng([seed, 29])
        objects = [
            replace(o, rgba=jitter_rgba(CATEGORIES[o.category].rgba, rng, j.hue, j.value, j.saturation))
            for o in objects
        ]
    if distractors is not None:
        objects += placer.distractors(distractors, seed, {o.name for o in objects})
    spec.objects = objects


def _place_objects(ctx, spec, entries, seed, clearance, tries):
    rng = np.random.default_rng(seed)
    placed: list[tuple[float, float, float]] = []  # x, y, footprint radius
    statics = spec.obstacles
    rx, ry, _ = spec.robot_start
    # wall ends: doorways are the gaps between them; keep random objects out of doorways
    ends = []
    for w in spec.walls:
        c, s = math.cos(w.yaw), math.sin(w.yaw)
        h = w.sx / 2
        ends += [(w.x - c * h, w.y - s * h), (w.x + c * h, w.y + s * h)]

    def free(x, y, r, margin, random=False):
        for ob in statics:
            if ob.distance(x, y) < r + margin:
                return False
        if random:
            for ex, ey in ends:
                if math.hypot(x - ex, y - ey) < DOOR_CLEARANCE + r:
                    return False
        if math.hypot(x - rx, y - ry) < ROBOT_RADIUS + r + margin:
            return False
        for px, py, pr in placed:
            if math.hypot(x - px, y - py) < r + pr + margin:
                return False
        return True

    # fixed poses first, so random ones avoid them
    for node, cat, name, room, pose in entries:
        if pose is None:
            continue
        r = CATEGORIES[cat].radius
        x0, y0, x1, y1 = spec.bounds
        if not (x0 + r <= pose[0] <= x1 - r and y0 + r <= pose[1] <= y1 - r):
            raise ctx.err(node, f"object '{name}': pose ({pose[0]}, {pose[1]}) is outside bounds {spec.bounds}")
        if not free(pose[0], pose[1], r, 0.0):
            raise ctx.err(
                node,
                f"object '{name}': pose ({pose[0]}, {pose[1]}) collides with a wall, "
                f"furniture, the robot start or another object",
            )
        placed.append((pose[0], pose[1], r))
    out = {}
    for node, cat, name, room, pose in entries:
        r = CATEGORIES[cat].radius
        if pose is not None:
            out[name] = PlacedObject(name, cat, pose[0], pose[1], pose[2])
            continue
        area = spec.rooms[room] if room else spec.bounds
        ax0, ay0, ax1, ay1 = area
        lo_x, hi_x = ax0 + r + clearance, ax1 - r - clearance
        lo_y, hi_y = ay0 + r + clearance, ay1 - r - clearance
        found = None
        if lo_x <= hi_x and lo_y <= hi_y:
            for _ in range(tries):
                x, y = rng.uniform(lo_x, hi_x), rng.uniform(lo_y, hi_y)
                if free(x, y, r, clearance, random=True):
                    found = (x, y)
                    break
        if found is None:
            where = f"room '{room}' {tuple(area)}" if room else f"bounds {tuple(area)}"
            raise ctx.err(
                node,
                f"cannot place object '{name}' ({cat}) in {where}: no free floor "
                f"space after {tries} tries (needs {clearance} m clearance from walls, "
                f"furniture, the robot start and the {len(placed)} objects already "
                f"placed, and {DOOR_CLEARANCE} m from doorways and wall ends); lower 'count' or "
                f"'placement.clearance', or enlarge the area",
            )
        yaw = float(rng.uniform(-math.pi, math.pi))
        placed.append((found[0], found[1], r))
        out[name] = PlacedObject(name, cat, float(found[0]), float(found[1]), yaw)
    # keep file order
    spec.objects = [out[e[2]] for e in entries]


def world_path(world: str | Path) -> Path:
    """Resolve a world name ('house') or a path to its YAML file."""
    p = Path(world)
    if p.suffix in (".yaml", ".yml") or p.exists():
        if not p.exists():
            raise WorldError(f"{p}: no such world file")
        return p
    cand = WORLDS_DIR / f"{world}.yaml"
    if not cand.exists():
        known = ", ".join(sorted(x.stem for x in WORLDS_DIR.glob("*.yaml")))
        raise WorldError(f"unknown world '{world}' (known: {known})")
    return cand


def load_world(
    world: str | Path | WorldSpec = "house", seed: int = 0, locations: str | Path | None = None
) -> WorldSpec:
    """Load a world by name or path (a WorldSpec passes through unchanged). A YAML file
    that is a map_server map (``image:``, ``resolution:``...) is built into a world by
    :mod:`sim.map_world`, with the named places of ``locations`` (a YAML file)."""
    if isinstance(world, WorldSpec):
        return world
    p = world_path(world)
    text = p.read_text()
    if is_map_yaml(text):
        return build_map_world(p, seed, locations)
    if locations is not None:
        raise WorldError(
            f"{locations}: a locations file goes with a world built from a map_server "
            f"map (--world map.yaml); {p} is a world description, which lists its own "
            "robot start, place_location and search_locations"
        )
    return parse_world(text, str(p), seed)


def list_worlds() -> list[str]:
    return sorted(x.stem for x in WORLDS_DIR.glob("*.yaml"))
