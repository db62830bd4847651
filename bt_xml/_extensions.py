"""actorbt's own XML nodes: what a mission says that BehaviorTree.CPP's built-ins cannot.

``actorbt xml export`` writes them only where no built-in says the same, and declares
each one it uses in the file's ``<TreeNodesModel>`` (so Groot2 shows and edits them like
any plugin node). ``actorbt xml import`` reads them back when the model declares them,
as it does Nav2's controls; undeclared, a tag of that name is an ordinary leaf.

==================  =========  ====================================================
node                kind       mission
==================  =========  ====================================================
ActorbtCheck        Condition  ``check: expr`` that has no exact BehaviorTree.CPP
                               script (``in``, fields, lists, ``null``)
ActorbtSet          Action     ``set:`` of several keys that a ``Script`` cannot
                               write (lists, mappings, fields, a key it also reads)
ActorbtWait         Action     ``wait: "{key}"`` (Sleep's msec takes no reference)
ActorbtTimeout      Decorator  ``timeout: {seconds: "{key}"}``
ActorbtParallel     Control    ``parallel`` with policy ``success_on_selected``
ActorbtRunOnce      Decorator  ``run_once then: success`` under a selector (a
                               RunOnce skip reads as a failure there)
ActorbtBehaviour    Action     ``behaviour: Name`` (a registered py_trees behaviour)
==================  =========  ====================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bt_engine.trees import ExprSyntaxError, keys_of, parse_expression
from ._errors import BtXmlError
from ._source import XElement

# The handlers take the importer (``_convert.Importer``, which imports this module) and
# its per-tree state; they are typed loosely so that the import goes one way.
Importer = Any
_Tree = Any

__all__ = ["EXTENSIONS", "NAV2_MODELS", "NodeDecl", "PortDecl", "LIST_SEPARATOR"]

#: separates names in one port (``selected``, ``writes``), as BehaviorTree.CPP separates vectors
LIST_SEPARATOR = ";"


@dataclass(frozen=True)
class PortDecl:
    """One port of a declared node: ``input_port`` or ``output_port``."""

    direction: str
    name: str
    type: str
    description: str
    default: str | None = None


@dataclass(frozen=True)
class NodeDecl:
    """A node the exporter declares in ``<TreeNodesModel>``."""

    kind: str
    id: str
    description: str
    ports: tuple[PortDecl, ...]


def _in(name: str, type_: str, text: str, default: str | None = None) -> PortDecl:
    return PortDecl("input_port", name, type_, text, default)


#: actorbt's nodes, by ID
EXTENSIONS: dict[str, NodeDecl] = {
    d.id: d
    for d in (
        NodeDecl(
            "Condition",
            "ActorbtCheck",
            "Succeeds when the actorbt check: expression holds on the blackboard.",
            (_in("expr", "std::string", "the expression, in actorbt's check language (docs/missions.md)"),),
        ),
        NodeDecl(
            "Action",
            "ActorbtSet",
            "Writes values to the blackboard (actorbt set:); always succeeds.",
            (_in("values", "dict", 'json: a mapping of key to value; a string "{key}" reads that key'),),
        ),
        NodeDecl(
            "Action",
            "ActorbtWait",
            "Running for the given time, then success (actorbt wait:).",
            (_in("seconds", "double", "how long [s]"),),
        ),
        NodeDecl(
            "Decorator",
            "ActorbtTimeout",
            "Halts the child and fails when it runs longer than the given time.",
            (_in("seconds", "double", "the time the child may run [s]"),),
        ),
        NodeDecl(
            "Control",
            "ActorbtParallel",
            "Ticks all children; succeeds when the selected ones have succeeded, fails when any fails.",
            (_in("selected", "std::string", "the names of the children that must succeed, separated by ';'"),),
        ),
        NodeDecl(
            "Decorator",
            "ActorbtRunOnce",
            "Ticks the child until it finishes once; afterwards returns 'then' without ticking it.",
            (_in("then", "std::string", "SUCCESS, FAILURE or SAME (the status the child finished with)", "SAME"),),
        ),
        NodeDecl(
            "Action",
            "ActorbtBehaviour",
            "A py_trees behaviour registered with actorbt, by name.",
            (
                _in("behaviour", "std::string", "the registered name"),
                _in("with", "dict", 'json: its keyword arguments; a string "{key}" reads that key'),
                _in("writes", "std::string", "the blackboard keys it writes, separated by ';'"),
            ),
        ),
    )
}

#: Nav2's control nodes that missions have, declared so that importers (and Groot2) know them
NAV2_MODELS: dict[str, NodeDecl] = {
    d.id: d
    for d in (
        NodeDecl(
            "Control", "PipelineSequence", "Nav2: ticks the children up to the furthest one reached, every tick.", ()
        ),
        NodeDecl(
            "Control",
            "RecoveryNode",
            "Nav2: runs the second child when the first fails, then tries the first again.",
            (_in("number_of_retries", "int", "how many times the first child is tried again", "1"),),
        ),
        NodeDecl(
            "Decorator",
            "RateController",
            "Nav2: ticks the child at most hz times a second.",
            (_in("hz", "double", "the rate [Hz]", "10.0"),),
        ),
        NodeDecl("Decorator", "SingleTrigger", "Nav2: ticks the child until it finishes once; afterwards fails.", ()),
    )
}


# ---------------------------------------------------------------- import


def _check(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("expr",), ("expr",))
    imp.children(el, ctx, "leaf", (0, 0))
    text = ports["expr"]
    try:
        expr = parse_expression(text)
    except ExprSyntaxError as exc:
        raise BtXmlError(el.value_pos("expr", exc.offset), f"bad check expression: {exc.message}") from None
    for key in keys_of(expr):
        ctx.read(key.name, el.at("expr"))
    return {"check": text}


def _mapping(imp: Importer, el: XElement, attr: str, text: str, ctx: _Tree) -> dict:
    value = imp.json_value(el, attr, text, ctx) if text.strip() else {}
    if not isinstance(value, dict):
        raise BtXmlError(el.at(attr), f"{attr} is {text!r}, expected json: and a JSON object")
    return value


def _set(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("values",), ("values",))
    imp.children(el, ctx, "leaf", (0, 0))
    values = _mapping(imp, el, "values", ports["values"], ctx)
    if not values:
        raise BtXmlError(el.at("values"), "values is empty, expected at least one key")
    for key in values:
        ctx.write(key, el.at("values"))
    return {"set": values}


def _wait(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("seconds",), ("seconds",))
    imp.children(el, ctx, "leaf", (0, 0))
    return {"wait": imp.number(el, "seconds", ports["seconds"], ctx, integer=False)}


def _timeout(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("seconds",), ("seconds",))
    seconds = imp.number(el, "seconds", ports["seconds"], ctx, integer=False)
    return {"timeout": {"seconds": seconds, "child": imp.child(el, ctx, "timeout")}}


def _names(text: str) -> list[str]:
    return [n.strip() for n in text.split(LIST_SEPARATOR) if n.strip()]


def _parallel(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("selected",), ("selected",))
    selected = _names(ports["selected"])
    kids = imp.children(el, ctx, "parallel")
    for kid, child in zip(kids, el.children):
        # a child named like its node ID lost its name on import: the selection needs it
        name = child.attrs.get("name")
        if name in selected and "name" not in kid:
            kid["name"] = name
    return {"parallel": {"policy": "success_on_selected", "selected": selected, "children": kids}}


def _run_once(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("then",))
    then = ports.get("then", "SAME").strip().lower()
    if then not in ("success", "failure", "same"):
        raise BtXmlError(el.at("then"), f"then is {ports['then']!r}, expected SUCCESS, FAILURE or SAME")
    return {"run_once": {"then": then, "child": imp.child(el, ctx, "run_once")}}


def _behaviour(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("behaviour", "with", "writes"), ("behaviour",))
    imp.children(el, ctx, "leaf", (0, 0))
    node: dict[str, Any] = {"behaviour": ports["behaviour"].strip()}
    kwargs = _mapping(imp, el, "with", ports.get("with", ""), ctx)
    if kwargs:
        node["with"] = kwargs
    writes = _names(ports.get("writes", ""))
    for key in writes:
        ctx.write(key, el.at("writes"))
    if writes:
        node["writes"] = writes
    return node


#: import handlers of actorbt's nodes (used when the node model declares them)
HANDLERS = {
    "ActorbtCheck": _check,
    "ActorbtSet": _set,
    "ActorbtWait": _wait,
    "ActorbtTimeout": _timeout,
    "ActorbtParallel": _parallel,
    "ActorbtRunOnce": _run_once,
    "ActorbtBehaviour": _behaviour,
}
