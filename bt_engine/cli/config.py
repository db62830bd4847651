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

Every command imports the plugins (``--help`` lists their commands), so a plugin keeps
only argparse wiring at module level and imports its implementation when it runs.
"""
from __future__ import annotations

import importlib
import pathlib
from dataclasses import dataclass, field
from typing import Any

import yaml

from ..errors import ActorbtError
from ..modules import import_file, is_file_reference
from ..yaml_hints import syntax_mark, syntax_message


class ConfigError(ActorbtError):
    """actorbt.yaml is missing a piece or names something that does not exist."""


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
    #: the ``mcp:`` section (read by :mod:`bt_engine.mcp.settings`)
    mcp: dict[str, Any] = field(default_factory=dict)

    @property
    def base(self) -> pathlib.Path:
        return self.path.parent if self.path else pathlib.Path.cwd()

    def trees_dir(self) -> pathlib.Path | None:
        return (self.base / self.trees) if self.trees else None


_FIELDS = {"subsystems", "trees", "world", "simulator", "transport", "clock", "plugins", "imports", "mcp"}


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
    return Config(path=p, subsystems=dict(data.get("subsystems") or {}),
                  trees=data.get("trees", "trees"), world=world,
                  simulator=data.get("simulator"), transport=data.get("transport", "local"),
                  clock=data.get("clock", "virtual"), plugins=list(data.get("plugins") or []),
                  imports=[str(i) for i in data.get("imports") or []], mcp=dict(mcp))


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
