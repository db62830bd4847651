"""Whether two parsed missions are the same tree: what the round trip through XML must
keep. Positions and the text of the file do not count; what a mission means does:

- the name, doc, inputs (type, default, doc) and outputs (type, doc), the texts without
  surrounding whitespace;
- every node's kind, label (its name, or what it shows without one: the trace paths),
  parameters and children, in order;
- values by :func:`~._values.same_value` (an int equals the same float; references by
  their dotted key), ``check:`` expressions by their syntax tree;
- a parallel by when it succeeds and fails: a policy and the counts that say the same
  (``success_on_one`` is ``success_count: 1, failure_count: 1``) are one parallel;
- an actor called with positional arguments is the same call as with those arguments
  by name, when ``signature`` names them.
"""

from __future__ import annotations

import dataclasses
import inspect
from typing import Any, Callable

from bt_engine.trees import (
    Check,
    Do,
    Expr,
    Mission,
    Node,
    Parallel,
    ParallelPolicy,
    PluginNode,
    RateController,
    Recovery,
    Repeat,
    Retry,
    RunOnce,
    SetValues,
    Timeout,
    UseBehaviour,
    Wait,
    children_of,
)
from ._values import same_value

__all__ = ["expr_shape", "mission_differences"]

Signature = Callable[[str], "inspect.Signature | None"]


def expr_shape(expr: Expr) -> Any:
    """A check expression's syntax tree without character offsets."""
    if dataclasses.is_dataclass(expr):
        return (
            type(expr).__name__,
            *(expr_shape(getattr(expr, f.name)) for f in dataclasses.fields(expr) if f.name != "offset"),
        )
    if isinstance(expr, tuple):
        return tuple(expr_shape(e) for e in expr)
    return (type(expr).__name__, expr) if isinstance(expr, (bool, int, float)) else expr


def mission_differences(a: Mission, b: Mission, signature: Signature | None = None) -> list[str]:
    """What differs between two missions, one line each (empty: the same tree)."""
    out: list[str] = []
    for what, x, y in (("name", a.name, b.name), ("doc", _text(a.doc), _text(b.doc))):
        if x != y:
            out.append(f"{a.name}: {what} {x!r} != {y!r}")
    ins = [[i.name, i.type.value, i.required, None if i.required else i.default, _text(i.doc)] for i in a.inputs]
    ins_b = [[i.name, i.type.value, i.required, None if i.required else i.default, _text(i.doc)] for i in b.inputs]
    if not same_value(ins, ins_b):
        out.append(f"{a.name}: inputs {ins} != {ins_b}")
    outs = [(o.name, o.type, _text(o.doc)) for o in a.outputs]
    outs_b = [(o.name, o.type, _text(o.doc)) for o in b.outputs]
    if outs != outs_b:
        out.append(f"{a.name}: outputs {outs} != {outs_b}")
    _nodes(a.root, b.root, a.name, out, signature)
    return out


def _text(doc: str | None) -> str | None:
    """Docs and descriptions without the surrounding whitespace (a YAML block ends in a
    newline; XML text is read stripped)."""
    return doc.strip() or None if doc is not None else None


def _nodes(a: Node, b: Node, path: str, out: list[str], signature: Signature | None) -> None:
    here = f"{path}/{a.label}"
    if a.label != b.label:
        out.append(f"{here}: label {a.label!r} != {b.label!r}")
    pa, pb = _params(a, signature), _params(b, signature)
    if pa[0] != pb[0] or not same_value(list(pa[1:]), list(pb[1:])):
        out.append(f"{here}: {pa} != {pb}")
        return
    kids_a, kids_b = children_of(a), children_of(b)
    if len(kids_a) != len(kids_b):
        out.append(f"{here}: {len(kids_a)} children != {len(kids_b)}")
        return
    for x, y in zip(kids_a, kids_b):
        _nodes(x, y, here, out, signature)


def _params(node: Node, signature: Signature | None) -> tuple[Any, ...]:
    """The node's kind and what it is parameterised with."""
    if isinstance(node, Parallel):
        n = len(node.children)
        if node.counted:
            s, f = node.success_count or -1, node.failure_count or 1
            return ("parallel", s if s > 0 else n + 1 + s, f if f > 0 else n + 1 + f)
        if node.policy is ParallelPolicy.SUCCESS_ON_ONE:
            return ("parallel", 1, 1)
        if node.policy is ParallelPolicy.SUCCESS_ON_ALL:
            return ("parallel", n, 1)
        return ("parallel", "selected", list(node.selected))
    if isinstance(node, Recovery):
        return (node.kind, node.retries)
    if isinstance(node, (Retry, Repeat)):
        return (node.kind, node.times)
    if isinstance(node, Timeout):
        return (node.kind, node.seconds)
    if isinstance(node, RateController):
        return (node.kind, node.hz)
    if isinstance(node, RunOnce):
        return (node.kind, node.then.value)
    if isinstance(node, Wait):
        return (node.kind, node.seconds)
    if isinstance(node, Check):
        return (node.kind, repr(expr_shape(node.expr)))
    if isinstance(node, SetValues):
        return (node.kind, list(node.values), list(node.values.values()))
    if isinstance(node, UseBehaviour):
        return (node.kind, node.behaviour, dict(node.kwargs), list(node.writes))
    if isinstance(node, PluginNode):
        return (node.kind, node.plugin, dict(node.ports), dict(node.outs))
    if isinstance(node, Do):
        return (node.kind, node.actor, _arguments(node, signature), node.out)
    return (node.kind,)


def _arguments(node: Do, signature: Signature | None) -> dict[str, Any]:
    if not node.args:
        return dict(node.kwargs)
    sig = signature(node.actor) if signature is not None else None
    names = (
        [p.name for p in sig.parameters.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
        if sig is not None
        else []
    )
    if len(names) < len(node.args):
        return {"*args": list(node.args), **node.kwargs}
    return {**dict(zip(names, node.args)), **node.kwargs}
