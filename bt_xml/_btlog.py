"""A recorded run (an actorbt JSONL trace) as a Groot2 log: the file BehaviorTree.CPP 4's
``FileLogger2`` writes (``.btlog``), which Groot2 replays.

Layout (all integers little-endian)::

    "BTCPP4-FileLogger2"  18 bytes, then the protocol version: 1 byte (1)
    N                     4 bytes: length of the XML
    XML                   N bytes: the tree, every node with a ``_uid`` attribute
    t0                    8 bytes: the first timestamp [us since the epoch]
    records               9 bytes each: timestamp since t0 [us] (6 bytes), node
                          uid (2 bytes), status (1 byte: 0 IDLE, 1 RUNNING,
                          2 SUCCESS, 3 FAILURE, 4 SKIPPED)

The XML is the tree as BehaviorTree.CPP instantiates it: the main tree, then one
``<BehaviorTree ID _fullpath>`` per SubTree *instance* (a tree called from two places is
there twice), nodes numbered depth first from 1, each SubTree node followed by its
instance's nodes. Nodes carry their mission labels as ``name``, so Groot2 shows the
names the trace paths use.

Every ``status`` event of the trace becomes one record: py_trees' INVALID is IDLE. A run
of a called tree is matched to the SubTree node whose call started it. ``t0`` is when the
trace was recorded (its header), and the records' times are the runtime clock's, from
the start of the recording: a virtual-clock run keeps its simulated timing.
"""

from __future__ import annotations

import datetime
import struct
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bt_engine.errors import ActorbtError
from bt_engine.trees import Do, Mission, Node, TreeLibrary, children_of, node_path
from bt_tools.replay import locate_trees, read_trace
from ._export import Exporter

__all__ = ["BTLOG_HEADER", "BtlogError", "STATUS_CODES", "Transition", "trace_to_btlog", "write_btlog"]

BTLOG_HEADER = b"BTCPP4-FileLogger2"
BTLOG_PROTOCOL = 1
#: py_trees status (as the trace writes it) -> BehaviorTree.CPP NodeStatus
STATUS_CODES = {"INVALID": 0, "RUNNING": 1, "SUCCESS": 2, "FAILURE": 3, "SKIPPED": 4}
_MAX_DELTA_US = (1 << 48) - 1
_MAX_UID = (1 << 16) - 1


class BtlogError(ActorbtError):
    """A trace cannot be converted: it does not match its trees, or does not fit the format."""


@dataclass(frozen=True)
class Transition:
    """One record: ``t_us`` after the first timestamp, node ``uid``, ``status`` code."""

    t_us: int
    uid: int
    status: int


@dataclass
class _Instance:
    """One instance of a tree in the expanded tree: its node uids by trace path, and the
    instance each SubTree node (by its path) starts."""

    mission: Mission
    fullpath: str
    uids: dict[str, int] = field(default_factory=dict)
    calls: dict[str, "_Instance"] = field(default_factory=dict)


class _Expander:
    """Builds the instantiated tree's XML, numbering nodes as BehaviorTree.CPP does."""

    def __init__(self, library: TreeLibrary) -> None:
        self.library = library
        self.exporter = Exporter(library)
        self.root = ET.Element("root", {"BTCPP_format": "4"})
        self.next_uid = 1
        self.trees: list[ET.Element] = []

    def instance(self, mission: Mission, fullpath: str) -> _Instance:
        inst = _Instance(mission, fullpath)
        tree = ET.Element("BehaviorTree", {"ID": mission.name, "_fullpath": fullpath})
        self.trees.append(tree)
        tree.append(self.node(mission.root, None, inst, node_path("", mission.root.label, set())))
        return inst

    def node(self, node: Node, parent: Node | None, inst: _Instance, path: str) -> ET.Element:
        element = self.exporter.element(node, parent)
        uid = self.next_uid
        if uid > _MAX_UID:
            raise BtlogError(f"the tree has more than {_MAX_UID} nodes, more than a Groot2 log numbers")
        self.next_uid += 1
        inst.uids[path] = uid
        first = {"ID": element.attrib.pop("ID")} if "ID" in element.attrib else {}
        element.attrib = {
            **first,
            "name": node.label,
            **{k: v for k, v in element.attrib.items() if k != "name"},
            "_uid": str(uid),
        }
        if isinstance(node, Do) and node.actor in self.library:
            sub_path = (inst.fullpath + "/" if inst.fullpath else "") + node.label
            element.set("_fullpath", sub_path)
            inst.calls[path] = self.instance(self.library[node.actor], sub_path)
        taken: set[str] = set()
        for child in children_of(node):
            element.append(self.node(child, node, inst, node_path(path, child.label, taken)))
        return element

    def xml(self) -> str:
        for tree in self.trees:
            self.root.append(tree)
        self.root.append(self.exporter.model_xml())
        return ET.tostring(self.root, encoding="unicode")


def _first_timestamp(header: dict[str, Any]) -> int:
    """When the trace was recorded [us since the epoch]; 0 when the header does not say."""
    recorded = header.get("recorded")
    if isinstance(recorded, str):
        try:
            stamp = datetime.datetime.fromisoformat(recorded)
        except ValueError:
            return 0
        if stamp.tzinfo is None:
            stamp = stamp.replace(tzinfo=datetime.timezone.utc)
        return max(0, round(stamp.timestamp() * 1e6))
    return 0


def trace_to_btlog(trace: str | Path, *, trees: str | Path | None = None) -> tuple[str, int, list[Transition]]:
    """The tree XML (with ``_uid``\\ s), first timestamp [us] and records of a trace.

    Args:
        trace: the ``.jsonl`` file.
        trees: a folder to find the tree files in by name; by default the paths the
            header recorded (as ``actorbt replay`` finds them).

    Raises:
        ReplayError: the trace cannot be read, or its trees cannot be found.
        MissionError: a tree file does not load.
        BtlogError: an event names a node or run its tree does not have.
    """
    trace = Path(trace)
    try:
        text = trace.read_bytes().decode("utf-8")
    except OSError as exc:
        raise BtlogError(f"{trace}: cannot read trace: {exc.strerror or exc}") from None
    except UnicodeDecodeError as exc:  # a binary file: a .btlog, a bag
        raise BtlogError(
            f"{trace}: not a trace: byte {exc.start} is not UTF-8 text, expected JSON lines "
            "(an actorbt trace, as run --record writes it)"
        ) from None
    header, events = read_trace(trace, text.splitlines())
    files, _notes = locate_trees(header, trace, trees)
    library = TreeLibrary()
    for path in files.values():
        library.load_file(path)
    name = header["tree"]
    if name not in library:
        raise BtlogError(f"{trace}: the header names tree {name!r}, but its trees are {', '.join(library.names)}")
    expander = _Expander(library)
    main = expander.instance(library[name], "")
    runs: dict[int, _Instance] = {}
    pending: dict[int, list[tuple[str, str]]] = {}  # run -> [(actor, caller path)] of tree calls not yet started
    records: list[Transition] = []
    for number, event in enumerate(events, 2):
        kind = event.get("type")
        if kind == "run":
            runs[event["run"]] = _run_instance(trace, number, event, runs, pending, main)
        elif kind == "call" and event.get("actor") in library:
            pending.setdefault(event["run"], []).append((event["actor"], event["path"]))
        elif kind == "status":
            inst = runs.get(event["run"])
            if inst is None:
                raise BtlogError(
                    f"{trace}:{number}: a status of run {event['run']}, which has not started, "
                    "expected a run event first"
                )
            uid = inst.uids.get(event["path"])
            if uid is None:
                raise BtlogError(
                    f"{trace}:{number}: tree {inst.mission.name!r} ({inst.mission.file}) has no node "
                    f"{event['path']!r}: was it changed since the recording?"
                )
            code = STATUS_CODES.get(event["new"])
            if code is None:
                raise BtlogError(
                    f"{trace}:{number}: status {event['new']!r}, expected one of {', '.join(STATUS_CODES)}"
                )
            t_us = round(float(event["t"]) * 1e6)
            if not 0 <= t_us <= _MAX_DELTA_US:
                raise BtlogError(
                    f"{trace}:{number}: time {event['t']} s is outside the log's range "
                    f"(0 to {_MAX_DELTA_US / 1e6:.0f} s after the start)"
                )
            if records and t_us < records[-1].t_us:
                t_us = records[-1].t_us  # the log's times never go back
            records.append(Transition(t_us, uid, code))
    return expander.xml(), _first_timestamp(header), records


def _run_instance(
    trace: Path,
    number: int,
    event: dict[str, Any],
    runs: dict[int, _Instance],
    pending: dict[int, list[tuple[str, str]]],
    main: _Instance,
) -> _Instance:
    parent = event.get("parent")
    if parent is None:
        if event["tree"] != main.mission.name:
            raise BtlogError(
                f"{trace}:{number}: run {event['run']} is tree {event['tree']!r}, expected the "
                f"header's tree {main.mission.name!r}"
            )
        return main
    caller = runs.get(parent)
    if caller is None:
        raise BtlogError(f"{trace}:{number}: run {event['run']} has parent run {parent}, which has not started")
    waiting = pending.get(parent, [])
    index = next((i for i, (actor, _) in enumerate(waiting) if actor == event["tree"]), None)
    if index is not None:
        _, path = waiting.pop(index)
        inst = caller.calls.get(path)
        if inst is not None:
            return inst
    # no call event: the one SubTree node of the caller that calls this tree
    found = [inst for inst in caller.calls.values() if inst.mission.name == event["tree"]]
    if not found:
        raise BtlogError(
            f"{trace}:{number}: run {event['run']} is tree {event['tree']!r}, which tree "
            f"{caller.mission.name!r} does not call"
        )
    return found[0]


def write_btlog(path: str | Path, xml: str, first_us: int, records: list[Transition]) -> Path:
    """Write a ``.btlog`` file (the layout in the module docstring)."""
    data = bytearray(BTLOG_HEADER)
    data.append(BTLOG_PROTOCOL)
    body = xml.encode("utf-8")
    data += struct.pack("<i", len(body))
    data += body
    data += struct.pack("<q", first_us)
    for record in records:
        data += record.t_us.to_bytes(6, "little") + struct.pack("<HB", record.uid, record.status)
    out = Path(path)
    try:
        out.write_bytes(bytes(data))
    except OSError as exc:
        raise BtlogError(f"{out}: cannot write: {exc.strerror or exc}") from None
    return out
