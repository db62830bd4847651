"""``actorbt.yaml``: what the ``actorbt`` command starts.

    subsystems:            # name: python path of a SubSystem class
      robot: actors.robot:Robot
    trees: trees           # folder of YAML missions, each registered as an actor
    world: {name: house, seed: 0}   # or null: nothing simulated
    simulator: sim:start_world      # how a world is started (python path)
    transport: local       # or ros
    clock: virtual         # default clock for run/call/shell/eval (serve uses wall)
    plugins: [sim.cli]     # modules adding `actorbt` sub-commands (register(subparsers, common))
    imports: [my_robot/juice.py]    # modules or .py files imported before anything starts:
                                    # what they register (an object category) is then known
    mcp: {allow_motion: false}      # `actorbt mcp`: may a client run actors that move the robot
    robot:                          # what --foxglove draws and --bag records of this robot
      body: {size: [0.281, 0.306, 0.141], x: -0.064}   # [m] a box at base_footprint
      topics:                       # recorded and shown besides /tf, /odom, /scan, /map ...
        - {name: /camera/color/image_raw, type: sensor_msgs/msg/Image, qos: sensor, compress: true}

Every command imports the plugins (``--help`` lists their commands), so a plugin keeps
only argparse wiring at module level and imports its implementation when it runs.
"""

from __future__ import annotations

import importlib
import pathlib
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import yaml

from bt_engine.errors import ActorbtError
from bt_engine.modules import import_file, is_file_reference
from bt_engine.yaml_hints import syntax_mark, syntax_message

if TYPE_CHECKING:
    from bt_ros.live_options import RobotSection


class ConfigError(ActorbtError):
    """actorbt.yaml is missing a piece or names something that does not exist."""


def _no_robot() -> RobotSection:
    return {"body": None, "topics": ()}


@dataclass
class Config:
    path: pathlib.Path | None = None
    subsystems: dict[str, str] = field(default_factory=dict)
    trees: str | None = "trees"
    world: dict[str, Any] | None = None
    simulator: str | None = None
    transport: str = "local"
    clock: str = "virtual"
    plugins: list[str] = field(default_factory=list)
    imports: list[str] = field(default_factory=list)
    #: the ``mcp:`` section (read by :mod:`bt_mcp.settings`)
    mcp: dict[str, Any] = field(default_factory=dict)
    #: the ``robot:`` section, checked: ``body`` (sx, sy, sz, x) [m] or None, and ``topics``,
    #: (name, type, qos, compress) each (read by :mod:`bt_ros.live_options`)
    robot: RobotSection = field(default_factory=_no_robot)

    @property
    def base(self) -> pathlib.Path:
        return self.path.parent if self.path else pathlib.Path.cwd()

    def trees_dir(self) -> pathlib.Path | None:
        return (self.base / self.trees) if self.trees else None


_FIELDS = {"subsystems", "trees", "world", "simulator", "transport", "clock", "plugins", "imports", "mcp", "robot"}
ROBOT_EXAMPLE = (
    "robot: {body: {size: [0.28, 0.31, 0.14], x: -0.06}, topics: [{name: /camera/image_raw, "
    "type: sensor_msgs/msg/Image, qos: sensor, compress: true}]}"
)


def find_config(start: pathlib.Path | None = None) -> pathlib.Path | None:
    """``actorbt.yaml`` in ``start`` or the nearest parent folder."""
    here = (start or pathlib.Path.cwd()).resolve()
    for d in (here, *here.parents):
        f = d / "actorbt.yaml"
        if f.is_file():
            return f
    return None


def load_config(path: "str | pathlib.Path | None" = None) -> Config:
    p = pathlib.Path(path) if path else find_config()
    if p is None:
        return Config()
    try:
        data = yaml.safe_load(p.read_text()) or {}
    except OSError as e:
        raise ConfigError(f"cannot read {p}: {e.strerror or e}") from None
    except yaml.MarkedYAMLError as e:
        mark = syntax_mark(e)
        where = f"{p}:{mark.line + 1}:{mark.column + 1}" if mark else str(p)
        raise ConfigError(f"{where}: {syntax_message(e)}") from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{p}: invalid YAML: {e}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{p}: expected a mapping of settings")
    unknown = set(data) - _FIELDS
    if unknown:
        raise ConfigError(f"{p}: unknown settings {sorted(unknown)}; expected {sorted(_FIELDS)}")
    mcp = data.get("mcp") or {}
    if not isinstance(mcp, dict):
        raise ConfigError(f"{p}: mcp: expected a mapping of settings, e.g. {{allow_motion: false}}")
    world = data.get("world")
    if isinstance(world, str):
        world = {"name": world}
    return Config(
        path=p,
        subsystems=dict(data.get("subsystems") or {}),
        trees=data.get("trees", "trees"),
        world=world,
        simulator=data.get("simulator"),
        transport=data.get("transport", "local"),
        clock=data.get("clock", "virtual"),
        plugins=list(data.get("plugins") or []),
        imports=[str(i) for i in data.get("imports") or []],
        mcp=dict(mcp),
        robot=_robot_section(p, data.get("robot")),
    )


def _robot_section(p: pathlib.Path, section: Any) -> RobotSection:
    """The checked ``robot:`` section: {"body": (sx, sy, sz, x) or None, "topics": ((name,
    type, qos, compress), ...)}; anything else is a ConfigError that shows the form."""

    def bad(what: str) -> ConfigError:
        return ConfigError(f"{p}: robot: {what}; for example {ROBOT_EXAMPLE}")

    section = {} if section is None else section
    if not isinstance(section, dict) or set(section) - {"body", "topics"}:
        raise bad("expected a mapping with body and topics")
    body = section.get("body")
    if body is not None:
        size = body.get("size") if isinstance(body, dict) else None
        if (
            not (isinstance(size, list) and len(size) == 3 and all(_positive(v) for v in size))
            or set(body) - {"size", "x"}
            or not _number(body.get("x", 0.0))
        ):
            raise bad(f"body: expected {{size: [x, y, z] in metres, x: offset}}, got {body!r}")
        body = (*(float(v) for v in size), float(body.get("x", 0.0)))
    topics = []
    for t in section.get("topics") or []:
        if (
            not isinstance(t, dict)
            or set(t) - {"name", "type", "qos", "compress"}
            or not str(t.get("name", "")).startswith("/")
            or str(t.get("type", "")).count("/") != 2
        ):
            raise bad(f"topics: expected {{name: /topic, type: pkg/msg/Type, qos: ..., compress: ...}}, got {t!r}")
        qos = t.get("qos", 10)
        try:
            from bt_engine.bus.qos import qos_depth

            qos_depth(qos)
        except ActorbtError as e:
            raise bad(f"topics: {t['name']}: {e}") from None
        compress = t.get("compress", False)
        if not isinstance(compress, bool) or (compress and t["type"] != "sensor_msgs/msg/Image"):
            raise bad(f"topics: {t['name']}: compress is true or false, and only for a sensor_msgs/msg/Image")
        topics.append((t["name"], t["type"], qos, compress))
    return {"body": body, "topics": tuple(topics)}


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _positive(v: Any) -> bool:
    return _number(v) and v > 0


def run_imports(cfg: Config) -> None:
    """Import what ``imports`` names: a module (``my_robot.juice``) or a .py file (relative
    to actorbt.yaml's folder). Each is imported once however often this runs."""
    for ref in cfg.imports:
        if is_file_reference(ref):
            path = pathlib.Path(ref).expanduser()
            path = path if path.is_absolute() else cfg.base / path
            if not path.is_file():
                raise ConfigError(f"{cfg.path}: imports: file {ref!r} not found (looked at {path.resolve()})")
            try:
                import_file(path)
            except Exception as e:
                raise ConfigError(f"{cfg.path}: imports: {ref!r} failed: {type(e).__name__}: {e}") from e
        else:
            try:
                importlib.import_module(ref)
            except ImportError as e:
                raise ConfigError(f"{cfg.path}: imports: cannot import {ref!r}: {e}") from None


def import_object(spec: str, what: str) -> Any:
    """``package.module:Name`` -> the object, with an error that says what was wanted."""
    mod_name, _, attr = spec.partition(":")
    try:
        mod = importlib.import_module(mod_name)
    except ImportError as e:
        raise ConfigError(f"cannot import {what} {spec!r}: {e}") from None
    if not attr:
        return mod
    try:
        return getattr(mod, attr)
    except AttributeError:
        raise ConfigError(f"{what} {spec!r}: module {mod_name} has no {attr!r}") from None
