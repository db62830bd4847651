"""Mission dicts written as YAML files: block style for the tree, flow style for
leaves (``{do: ComputePathToPose, with: {goal: "{goal}"}, out: path}``), so that the
file reads like a hand-written mission."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

__all__ = ["dump_mission", "write_missions"]


class _Flow(dict):
    """A mapping written in flow style."""


class _Dumper(yaml.SafeDumper):
    pass


_Dumper.add_representer(_Flow, lambda d, data: d.represent_mapping("tag:yaml.org,2002:map", data, flow_style=True))


def _is_flat(value: Any) -> bool:
    if isinstance(value, dict):
        return all(not isinstance(v, (dict, list)) or _is_flat_value(v) for v in value.values())
    return False


def _is_flat_value(value: Any) -> bool:
    if isinstance(value, dict):
        return all(not isinstance(v, (dict, list)) for v in value.values())
    if isinstance(value, list):
        return all(not isinstance(v, (dict, list)) for v in value)
    return True


def _mark(value: Any, top: bool = False) -> Any:
    if isinstance(value, dict):
        marked = {k: _mark(v) for k, v in value.items()}
        return _Flow(marked) if not top and _is_flat(value) else marked
    if isinstance(value, list):
        return [_mark(v) for v in value]
    return value


def dump_mission(mission: dict, source: str = "") -> str:
    """The mission as YAML text, with a header comment naming its source."""
    header = f"# Imported from {source} by `actorbt xml import`.\n" if source else ""
    body = {k: (_mark(v) if k == "root" else v) for k, v in mission.items()}
    return header + yaml.dump(body, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=110)


def write_missions(missions: dict[str, dict], out: str | Path, source: str = "") -> list[Path]:
    """Write one ``NAME.yaml`` per mission into ``out`` (created); returns the paths."""
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for name, mission in missions.items():
        path = folder / f"{name}.yaml"
        path.write_text(dump_mission(mission, source), encoding="utf-8")
        paths.append(path)
    return paths
