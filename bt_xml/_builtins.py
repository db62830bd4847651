"""BehaviorTree.CPP's built-in nodes (and Nav2's controls) converted to mission nodes:
one handler per node, ``handler(importer, element, node_id, ports, tree, parent) ->
mission dict``, and the nodes that have no mission equivalent, with the reason.

The importer (``_convert.Importer``) calls these and they call back its helpers
(``params``, ``children``, ``number``, ``input_value``...); they take it untyped so that
the import goes one way.
"""

from __future__ import annotations

import re
from typing import Any, Callable

from ._errors import BtXmlError, UnsupportedXmlError
from ._nodes import guess_literal
from ._source import XElement

__all__ = ["BUILTINS", "NAV2", "UNSUPPORTED", "Handler"]

Importer = Any
_Tree = Any
Handler = Callable[[Importer, XElement, str, "dict[str, str]", _Tree, str], dict]

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_SELECTORS = ("selector", "reactive_selector")


def _status_node(imp: Importer, el: XElement, attr: str, text: str, parent: str) -> dict:
    status = text.strip().upper()
    if status == "SUCCESS":
        return {"name": "success", "check": "true"}
    if status == "FAILURE":
        return {"name": "failure", "check": "false"}
    if status == "SKIPPED":
        return imp.skipped(parent)
    if status == "RUNNING":
        return {"name": "running", "behaviour": "Running"}
    raise BtXmlError(el.at(attr), f"{attr} is {text!r}, expected SUCCESS, FAILURE, SKIPPED or RUNNING")


def _composite(kind: str) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ())
        return {kind: imp.children(el, ctx, kind)}

    return handler


def _decorator(kind: str) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ())
        return {kind: imp.child(el, ctx, kind)}

    return handler


def _parallel(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("success_count", "failure_count", "success_threshold", "failure_threshold"))
    kids = imp.children(el, ctx, "parallel")
    counts = {}
    for attr, alias, default in (("success_count", "success_threshold", -1), ("failure_count", "failure_threshold", 1)):
        name = attr if attr in ports else alias
        value = imp.number(el, name, ports[name], ctx, integer=True, ref_ok=False) if name in ports else default
        if value == 0 or abs(value) > len(kids):
            raise BtXmlError(el.at(name), f"{name} is {value}, expected 1 to {len(kids)} or -1 to -{len(kids)}")
        counts[attr] = value
    if counts in ({"success_count": -1, "failure_count": 1}, {"success_count": len(kids), "failure_count": 1}):
        return {"parallel": kids}
    if counts["success_count"] == 1 and counts["failure_count"] == 1:
        return {"parallel": {"policy": "success_on_one", "children": kids}}
    return {"parallel": {**counts, "children": kids}}


def _branching(kind: str) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ())
        return {kind: imp.children(el, ctx, kind, (2, 3))}

    return handler


def _retry(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("num_attempts",), ("num_attempts",))
    times = imp.number(el, "num_attempts", ports["num_attempts"], ctx, integer=True)
    if times == -1:
        times = "forever"
    elif isinstance(times, int) and times < 1:
        raise BtXmlError(el.at("num_attempts"), f"num_attempts is {times}, expected -1 (no limit) or >= 1")
    return {"retry": {"times": times, "child": imp.child(el, ctx, "retry")}}


def _repeat(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("num_cycles",), ("num_cycles",))
    times = imp.number(el, "num_cycles", ports["num_cycles"], ctx, integer=True)
    if isinstance(times, int) and times != -1 and times < 1:
        raise BtXmlError(el.at("num_cycles"), f"num_cycles is {times}, expected -1 (forever) or >= 1")
    child = imp.child(el, ctx, "repeat")
    return {"repeat": {"child": child} if times == -1 else {"times": times, "child": child}}


def _timeout(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("msec",), ("msec",))
    seconds = imp.number(el, "msec", ports["msec"], ctx, integer=False, scale=0.001, ref_ok=False)
    if seconds <= 0:
        raise BtXmlError(el.at("msec"), "msec is not positive, expected a timeout > 0")
    return {"timeout": {"seconds": seconds, "child": imp.child(el, ctx, "timeout")}}


def _delay(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("delay_msec",), ("delay_msec",))
    seconds = imp.number(el, "delay_msec", ports["delay_msec"], ctx, integer=False, scale=0.001, ref_ok=False)
    return {"sequence": [{"wait": seconds}, imp.child(el, ctx, "sequence")]}


def _keep_running(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ())
    return {"repeat": {"child": imp.child(el, ctx, "repeat")}}


def _run_once(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("then_skip",))
    skip = ports.get("then_skip", "true").strip().lower()
    if skip not in ("true", "false"):
        raise BtXmlError(el.at("then_skip"), f"then_skip is {ports['then_skip']!r}, expected true or false")
    then = ("failure" if parent in _SELECTORS else "success") if skip == "true" else "same"
    return {"run_once": {"then": then, "child": imp.child(el, ctx, "run_once")}}


def _precondition(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("if", "else"), ("if",))
    test = imp.check(el, "if", ports["if"], ctx)
    otherwise = _status_node(imp, el, "else", ports.get("else", "FAILURE"), parent)
    return {"if_then_else": [test, imp.child(el, ctx, "if_then_else"), otherwise]}


def _always(value: str) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        imp.params(el, ports, ())
        imp.children(el, ctx, "leaf", (0, 0))
        return {"name": node_id, "check": value}

    return handler


def _sleep(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("msec",), ("msec",))
    imp.children(el, ctx, "leaf", (0, 0))
    return {"wait": imp.number(el, "msec", ports["msec"], ctx, integer=False, scale=0.001, ref_ok=False)}


def _set_blackboard(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("value", "output_key"), ("value", "output_key"))
    imp.children(el, ctx, "leaf", (0, 0))
    text = ports["output_key"].strip()
    key = imp.key(el, "output_key", text) or (text if _IDENT.match(text) else None)
    if key is None:
        raise BtXmlError(el.at("output_key"), f"output_key is {text!r}, expected a blackboard key")
    ctx.write(key, el.at("output_key"))
    return {"set": {key: imp.input_value(el, "value", ports["value"], ctx)}}


def _script(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("code",), ("code",))
    imp.children(el, ctx, "leaf", (0, 0))
    nodes = imp.script(el, "code", ports["code"], ctx)
    if not nodes:
        return {"check": "true"}
    return nodes[0] if len(nodes) == 1 else {"sequence": nodes}


def _script_condition(
    imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str
) -> dict:
    imp.params(el, ports, ("code",), ("code",))
    imp.children(el, ctx, "leaf", (0, 0))
    return imp.check(el, "code", ports["code"], ctx)


def _switch(n: int) -> Handler:
    def handler(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
        cases = [f"case_{i}" for i in range(1, n + 1)]
        imp.params(el, ports, ("variable", *cases), ("variable", *cases))
        key = imp.key(el, "variable", ports["variable"])
        if key is None:
            raise BtXmlError(el.at("variable"), 'variable must be a blackboard key such as "{state}"')
        ctx.read(key, el.at("variable"))
        kids = imp.children(el, ctx, "while_do_else", (n + 1, n + 1))
        node = kids[-1]
        for case, kid in reversed(list(zip(cases, kids))):
            value = guess_literal(ports[case])
            shown = (
                f'"{value}"'
                if isinstance(value, str)
                else ("true" if value is True else "false" if value is False else repr(value))
            )
            if isinstance(value, str) and ('"' in value or "\\" in value):
                raise UnsupportedXmlError(el.at(case), f"{case} {value!r}: quotes and backslashes are not supported")
            node = {"while_do_else": [{"check": f"{key} == {shown}"}, kid, node]}
        return node

    return handler


def _pipeline(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ())
    return {"pipeline_sequence": imp.children(el, ctx, "pipeline_sequence")}


def _recovery(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("number_of_retries",))
    retries = imp.number(el, "number_of_retries", ports.get("number_of_retries", "1"), ctx, integer=True)
    return {"recovery": {"retries": retries, "children": imp.children(el, ctx, "recovery", (2, 2))}}


def _rate(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ("hz",))
    hz = imp.number(el, "hz", ports.get("hz", "10"), ctx, integer=False)
    return {"rate_controller": {"hz": hz, "child": imp.child(el, ctx, "rate_controller")}}


def _single_trigger(imp: Importer, el: XElement, node_id: str, ports: dict[str, str], ctx: _Tree, parent: str) -> dict:
    imp.params(el, ports, ())
    return {"run_once": {"then": "failure", "child": imp.child(el, ctx, "run_once")}}


#: BehaviorTree.CPP's built-in nodes
BUILTINS: dict[str, Handler] = {
    "Sequence": _composite("sequence"),
    "ReactiveSequence": _composite("reactive_sequence"),
    "SequenceWithMemory": _composite("resume_sequence"),
    # BehaviorTree.CPP 3's name for it (Nav2 Humble's trees still use it)
    "SequenceStar": _composite("resume_sequence"),
    "Fallback": _composite("selector"),
    "ReactiveFallback": _composite("reactive_selector"),
    "Parallel": _parallel,
    "IfThenElse": _branching("if_then_else"),
    "WhileDoElse": _branching("while_do_else"),
    **{f"Switch{n}": _switch(n) for n in range(2, 7)},
    "Inverter": _decorator("invert"),
    "ForceSuccess": _decorator("force_success"),
    "ForceFailure": _decorator("force_failure"),
    "RetryUntilSuccessful": _retry,
    "Repeat": _repeat,
    "Timeout": _timeout,
    "Delay": _delay,
    "KeepRunningUntilFailure": _keep_running,
    "RunOnce": _run_once,
    "Precondition": _precondition,
    "AlwaysSuccess": _always("true"),
    "AlwaysFailure": _always("false"),
    "Sleep": _sleep,
    "SetBlackboard": _set_blackboard,
    "Script": _script,
    "ScriptCondition": _script_condition,
}

#: Nav2's control nodes, mapped when the XML or the node model says they are controls
NAV2: dict[str, Handler] = {
    "PipelineSequence": _pipeline,
    "RecoveryNode": _recovery,
    "RateController": _rate,
    "SingleTrigger": _single_trigger,
}

#: BehaviorTree.CPP nodes with no mission equivalent, and why
UNSUPPORTED: dict[str, str] = {
    "UnsetBlackboard": "missions never remove a blackboard key (a key holds a value once written)",
    "WasEntryUpdated": "missions do not track when a key was last written",
    "SkipUnlessUpdated": "missions do not track when a key was last written",
    "WaitValueUpdate": "missions do not track when a key was last written",
    "LoopInt": "queues on the blackboard are not supported; loop in an actor",
    "LoopDouble": "queues on the blackboard are not supported; loop in an actor",
    "LoopString": "queues on the blackboard are not supported; loop in an actor",
    "LoopBool": "queues on the blackboard are not supported; loop in an actor",
    "ParallelAll": "use Parallel with success_count and failure_count",
    "ManualSelector": "it asks a human at a terminal, which a mission does not do",
    "SubTreePlus": 'it is BehaviorTree.CPP v3; use <SubTree ... _autoremap="true">',
}
