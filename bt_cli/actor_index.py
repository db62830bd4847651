"""The actor index: every actor of the configured subsystems, without a runtime.

Commands that only need to know the actors (``check``, ``list``, ``catalog``) read it
from ``.actorbt/actors.json`` beside actorbt.yaml. It is rebuilt, by constructing the
subsystems in a runtime without a world, when the configured subsystems change or a
source file it was built from changes size or modification time. Building it imports
the robot's code (planning, pybullet, ROS messages); reading it imports none of that.
"""

from __future__ import annotations

import inspect
import json
import logging
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from bt_engine.actor import ActorRef, Safety
from bt_engine.catalog import text_lines, tool_schema
from bt_engine.errors import AmbiguousActorError, UnknownActorError

log = logging.getLogger("actorbt.cli")


#: bump when the layout of actors.json changes (2: tools carry parameter descriptions,
#: units, details and returns; 3: moves, read_only and limits)
INDEX_VERSION = 3


class _Shown:
    """A default value or annotation known by how it prints (read back from the index)."""

    __slots__ = ("text",)

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return self.text


@dataclass(frozen=True)
class ActorEntry:
    """One actor as the index keeps it; what the tree validator needs of an ActorRef
    (``path``, ``signature``, ``is_tree``) and what ``list`` and ``catalog`` print."""

    path: str
    name: str
    kind: str
    is_tree: bool
    doc: str
    signature: inspect.Signature
    #: ``str(signature)`` of the actor itself, as ``actorbt list`` prints it
    shown: str
    #: its JSON-Schema tool description (bt_engine.catalog.tool_schema)
    tool: dict[str, Any]

    @classmethod
    def of(cls, ref: ActorRef) -> "ActorEntry":
        return cls(
            ref.path,
            ref.name,
            ref.kind.value,
            ref.is_tree,
            ref.doc,
            ref.signature,
            str(ref.signature),
            tool_schema(ref),
        )

    @property
    def safety(self) -> Safety:
        """What the actor declared: motion, and its limits (read back from the tool's
        parameters' minimum / maximum, of their items for ``*args``)."""
        limits = {}
        for name, schema in self.tool.get("parameters", {}).get("properties", {}).items():
            bounds = schema if "minimum" in schema or "maximum" in schema else schema.get("items", {})
            if "minimum" in bounds or "maximum" in bounds:
                limits[name] = (bounds.get("minimum"), bounds.get("maximum"))
        return Safety(moves=bool(self.tool.get("moves")), read_only=bool(self.tool.get("read_only")), limits=limits)

    def text_lines(self) -> list[str]:
        """What ``actorbt catalog`` prints below the signature: the docstring without
        its ``Args:`` section, then one line per parameter (description, type, default)."""
        return text_lines(self.doc, self.tool)

    def to_json(self) -> dict[str, Any]:
        sig = self.signature
        return {
            "path": self.path,
            "name": self.name,
            "kind": self.kind,
            "is_tree": self.is_tree,
            "doc": self.doc,
            "shown": self.shown,
            "tool": self.tool,
            "params": [
                {
                    "name": p.name,
                    "kind": p.kind.name,
                    "annotation": _annotation_out(p.annotation),
                    **({} if p.default is p.empty else {"default": repr(p.default)}),
                }
                for p in sig.parameters.values()
            ],
            "returns": _annotation_out(sig.return_annotation),
        }

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> "ActorEntry":
        empty = inspect.Parameter.empty
        params = [
            inspect.Parameter(
                p["name"],
                getattr(inspect.Parameter, p["kind"]),
                default=_Shown(p["default"]) if "default" in p else empty,
                annotation=_annotation_in(p["annotation"]),
            )
            for p in d["params"]
        ]
        sig = inspect.Signature(params, return_annotation=_annotation_in(d["returns"]))
        return cls(d["path"], d["name"], d["kind"], d["is_tree"], d["doc"], sig, d["shown"], d["tool"])


def _annotation_out(annotation: Any) -> dict[str, Any] | None:
    """An annotation as text plus the tree value type it demands (what the validator checks)."""
    if annotation is inspect.Parameter.empty:
        return None
    from bt_engine.trees import annotation_text, annotation_type

    vtype = annotation_type(annotation)
    return {"text": annotation_text(annotation), "type": vtype.value if vtype else None}


def _annotation_in(d: dict[str, Any] | None) -> Any:
    if d is None:
        return inspect.Parameter.empty
    from bt_engine.trees import ValueType, annotation_type

    vtype = ValueType(d["type"]) if d["type"] else None
    if annotation_type(d["text"]) == vtype:
        return d["text"]  # as a postponed annotation: "float", "list[float]", "Twist"
    return vtype.python_type if vtype else _Shown(d["text"])


class ActorIndex:
    """The actors of a runtime's subsystems, without the runtime.

    :meth:`resolve` looks a name up as ``rt.root.resolve`` does (a dotted path, a root
    actor, else the one actor of that name below the root), so the tree validator can
    take it as its resolver.
    """

    def __init__(self, entries: Iterable[ActorEntry]) -> None:
        self.entries = sorted(entries, key=lambda e: e.path)
        self._by_path = {e.path: e for e in self.entries}

    @classmethod
    def of(cls, refs: Iterable[ActorRef]) -> "ActorIndex":
        return cls(ActorEntry.of(r) for r in refs)

    def resolve(self, name: str) -> ActorEntry:
        """The actor ``name`` as the root scope sees it.

        Raises:
            UnknownActorError: no such actor (``.suggestions`` lists close names).
            AmbiguousActorError: several subsystems below the root define ``name``.
        """
        entry = self._by_path.get(name)  # a dotted path, or a root actor
        if entry is not None:
            return entry
        if name and "." not in name:
            found = [e for e in self.entries if "." in e.path and e.name == name]
            if len(found) == 1:
                return found[0]
            if found:
                raise AmbiguousActorError(name, [e.path for e in found])
        raise UnknownActorError(str(name), [e.path for e in self.entries] + [e.name for e in self.entries])

    # -- storage -------------------------------------------------------------------------
    def save(self, path: Path, subsystems: dict[str, str], sources: dict[str, list[int]]) -> None:
        """Write the index with what it depends on; a folder we cannot write is no error."""
        data = {
            "version": INDEX_VERSION,
            "subsystems": subsystems,
            "sources": sources,
            "actors": [e.to_json() for e in self.entries],
        }
        tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp.write_text(json.dumps(data, indent=1, default=str), encoding="utf-8")
            os.replace(tmp, path)  # readers see the old file or the new one, never half
        except OSError as e:
            log.debug("cannot store the actor index in %s: %s", path, e)
            tmp.unlink(missing_ok=True)

    @classmethod
    def load(cls, path: Path, subsystems: dict[str, str]) -> "ActorIndex | None":
        """The stored index, or ``None`` when it is missing, unreadable or out of date:
        other subsystems configured, or a source file changed since it was built."""
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if data.get("version") != INDEX_VERSION or data.get("subsystems") != subsystems:
                return None
            for file, stamp in data["sources"].items():
                st = os.stat(file)
                if [st.st_mtime_ns, st.st_size] != stamp:
                    return None
            return cls(ActorEntry.from_json(d) for d in data["actors"])
        except (OSError, ValueError, KeyError, TypeError) as e:
            log.debug("actor index %s not used: %s", path, e)
            return None


def loaded_sources(specs: Iterable[str]) -> dict[str, list[int]]:
    """``file -> [mtime_ns, size]`` of every Python module loaded now from outside the
    interpreter's own folders (the project's code: engine, actors, planning...), and of
    the modules actorbt.yaml names wherever they are installed."""
    interpreter = tuple(os.path.join(p, "") for p in {sys.prefix, sys.base_prefix, sys.exec_prefix})
    named = {spec.partition(":")[0] for spec in specs}
    out: dict[str, list[int]] = {}
    for mod_name, module in list(sys.modules.items()):
        file = getattr(module, "__file__", None)
        if not file or (file.startswith(interpreter) and mod_name not in named):
            continue
        try:
            st = os.stat(file)
        except OSError:
            continue
        out[file] = [st.st_mtime_ns, st.st_size]
    return out
