"""From position-keeping YAML to the typed mission model: structure and local checks.

Everything that can be checked from the file alone is checked here (fields, value
types and ranges, ``check:`` syntax, reference syntax). What needs the actors or other
trees (names, signatures, blackboard data flow, cycles) is in ``_validate``.
"""

from __future__ import annotations

import codecs
import difflib
import keyword
import re
from pathlib import Path
from typing import Any, Iterable

from ._errors import (
    CheckExpressionError,
    InvalidValueError,
    LimitError,
    MissionError,
    MissionSyntaxError,
    Pos,
    UnknownFieldError,
    UnknownNodeError,
    shorten,
)
from ._expr import ExprSyntaxError, keys_of, parse_expression
from ._model import (
    REQUIRED,
    Check,
    Composite,
    Condition,
    Do,
    ForceFailure,
    ForceSuccess,
    InputSpec,
    IfThenElse,
    Invert,
    Mission,
    Node,
    OutputSpec,
    Parallel,
    ParallelPolicy,
    PipelineSequence,
    PluginControl,
    PluginDecorator,
    RateController,
    ReactiveSelector,
    ReactiveSequence,
    Recovery,
    Ref,
    Repeat,
    ResumeSequence,
    Retry,
    RunOnce,
    RunOnceThen,
    Selector,
    Sequence,
    SetValues,
    Timeout,
    UseBehaviour,
    ValueType,
    Wait,
    WhileDoElse,
)
from ._yaml import YMap, YNode, YScalar, YSeq, parse_yaml, plain

__all__ = ["MAX_MISSION_SIZE", "MISSION_FIELDS", "NODE_TYPES", "parse_mission", "read_mission", "suggest"]

MISSION_FIELDS = ("name", "doc", "inputs", "outputs", "root")

#: Largest mission, in bytes read from a file or characters given as text. Real
#: missions are a few kilobytes; this bounds the time one file can take (pure-Python
#: YAML reads a dense mission at roughly 100 kB/s: a few seconds at most).
MAX_MISSION_SIZE = 250_000

_COMPOSITES: dict[str, type[Composite]] = {
    "sequence": Sequence,
    "reactive_sequence": ReactiveSequence,
    "selector": Selector,
    "fallback": Selector,
    "reactive_selector": ReactiveSelector,
    "reactive_fallback": ReactiveSelector,
    "parallel": Parallel,
    "resume_sequence": ResumeSequence,
    "pipeline_sequence": PipelineSequence,
    "if_then_else": IfThenElse,
    "while_do_else": WhileDoElse,
    "recovery": Recovery,
}
_SIMPLE_DECORATORS = {"invert": Invert, "force_success": ForceSuccess, "force_failure": ForceFailure}
_DECORATOR_FIELDS = {
    "retry": ("times", "child"),
    "repeat": ("times", "child"),
    "timeout": ("seconds", "child"),
    "rate_controller": ("hz", "child"),
    "run_once": ("then", "child"),
}
_DECORATOR_EXAMPLES = {
    "retry": "{times: 3, child: {do: pick}}",
    "repeat": "{times: 2, child: {do: scan}}",
    "timeout": "{seconds: 20, child: {do: arm_home}}",
    "rate_controller": "{hz: 1.0, child: {do: plan_path}}",
    "run_once": "{then: success, child: {do: calibrate}}",
}
# composites whose children are a condition and one or two branches
_BRANCHING = ("if_then_else", "while_do_else")
_LEAVES = ("do", "condition", "set", "check", "wait", "behaviour")
# controls and decorators written in Python, by their registered name
_PLUGINS = ("control", "decorator")

#: Every node type keyword, in the order the docs list them.
NODE_TYPES: tuple[str, ...] = (*_COMPOSITES, *_DECORATOR_FIELDS, *_SIMPLE_DECORATORS, *_PLUGINS, *_LEAVES)

# Fields a node may carry besides its type keyword.
_NODE_FIELDS: dict[str, tuple[str, ...]] = {
    "do": ("with", "out"),
    "condition": ("with", "out"),
    "behaviour": ("with", "writes"),
    "control": ("with", "out", "children"),
    "decorator": ("with", "out", "child"),
}

_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
_ACTOR_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*\Z")
_REF = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)((?:\.[A-Za-z][A-Za-z0-9_]*)*)\}\Z")
_INNER_REF = re.compile(r"(?<!\{)\{[A-Za-z_][A-Za-z0-9_.]*\}(?!\})")


#: Most choices :func:`suggest` compares a word with (difflib takes ~10 us a choice).
MAX_SUGGESTION_CHOICES = 500


def suggest(word: str, choices: Iterable[str]) -> str:
    """``" (did you mean 'x'?)"`` for the closest choice, or ``""`` (also when there are
    more than MAX_SUGGESTION_CHOICES to compare with)."""
    choices = list(choices)
    if len(choices) > MAX_SUGGESTION_CHOICES:
        return ""
    close = difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    return f" (did you mean {shorten(close[0])}?)" if close else ""


def _kind(node: YNode) -> str:
    if isinstance(node, YMap):
        return "a mapping"
    if isinstance(node, YSeq):
        return "a list"
    if node.value is None:
        return "nothing"
    return f"{type(node.value).__name__} {shorten(node.raw)}"


class _Parser:
    def __init__(self, file: str, source: str) -> None:
        self.file = file
        self.source = source

    # ------------------------------------------------------------ helpers

    def check_fields(self, m: YMap, allowed: Iterable[str], what: str) -> None:
        allowed = tuple(allowed)
        for key, _ in m.items:
            if key.raw not in allowed:
                raise UnknownFieldError(
                    key.pos,
                    f"unknown field {shorten(key.raw)} in {what}{suggest(key.raw, allowed)}, "
                    f"expected one of: {', '.join(allowed)}",
                )

    def string(self, node: YNode, what: str) -> str:
        if not isinstance(node, YScalar) or not isinstance(node.value, str):
            raise InvalidValueError(node.pos, f"{what} must be a string, got {_kind(node)}")
        return node.value

    def ident(self, node: YNode, what: str) -> str:
        text = self.string(node, what)
        if not _IDENT.match(text):
            raise InvalidValueError(
                node.pos,
                f"{what} {shorten(text)} is not a valid name, expected letters, digits and '_' (e.g. target_pose)",
            )
        return text

    def mapping(self, node: YNode, what: str, example: str) -> YMap:
        if not isinstance(node, YMap):
            raise InvalidValueError(node.pos, f"{what} must be a mapping, got {_kind(node)}; expected e.g. {example}")
        return node

    def number(
        self, node: YNode, what: str, *, integer: bool, minimum: float, words: dict[str, Any] | None = None
    ) -> Any:
        """A literal number >= minimum, a whole-string reference, or one of ``words``."""
        if isinstance(node, YScalar) and isinstance(node.value, str):
            if words and node.value in words:
                return words[node.value]
            ref = self.ref(node)
            if ref is not None:
                return ref
        expected = base = "an integer" if integer else "a number"
        if words:
            expected += " or " + " or ".join(repr(w) for w in words)
        value = node.value if isinstance(node, YScalar) else None
        ok_types = (int,) if integer else (int, float)
        if not isinstance(node, YScalar) or isinstance(value, bool) or not isinstance(value, ok_types):
            raise InvalidValueError(node.pos, f'{what} must be {expected} or a "{{key}}" reference, got {_kind(node)}')
        if value < minimum or value != value:  # NaN
            raise InvalidValueError(node.pos, f"{what} is {value!r}, expected {base} >= {minimum:g}")
        return value

    # ------------------------------------------------------------ values and references

    def ref(self, node: YScalar) -> Ref | None:
        match = _REF.match(node.value)
        if match is None:
            return None
        fields = tuple(f for f in match.group(2).split(".") if f)
        return Ref(match.group(1), fields, node.text_pos.shifted(1))

    def value(self, node: YNode) -> Any:
        """A plain value where whole-string ``"{key}"`` becomes a :class:`Ref`."""
        if isinstance(node, YScalar):
            if not isinstance(node.value, str):
                return node.value
            ref = self.ref(node)
            if ref is not None:
                return ref
            inner = _INNER_REF.search(node.value)
            if inner is not None:
                raise InvalidValueError(
                    node.pos_at(inner.start()),
                    f"{inner.group(0)} inside the string {shorten(node.value)}: a blackboard reference must be "
                    f'the whole string, expected "{inner.group(0)}" alone (write {{{{ }}}} for literal braces)',
                )
            return node.value.replace("{{", "{").replace("}}", "}")
        if isinstance(node, YSeq):
            return [self.value(item) for item in node.items]
        if len(node) == 1:
            key, val = node.items[0]
            if isinstance(val, YScalar) and val.value is None and val.raw == "" and _IDENT.match(key.raw):
                raise InvalidValueError(
                    node.pos,
                    f'unquoted {{{key.raw}}} is a YAML mapping, expected the quoted reference "{{{key.raw}}}"',
                )
        return {k.raw: self.value(v) for k, v in node.items}

    # ------------------------------------------------------------ mission

    def mission(self) -> Mission:
        top = parse_yaml(self.source, self.file)
        if top is None:
            raise MissionSyntaxError(
                Pos(self.file, 1, 1), "empty mission file, expected a mapping with 'name' and 'root'"
            )
        if not isinstance(top, YMap):
            raise InvalidValueError(
                top.pos, f"a mission must be a mapping, got {_kind(top)}; expected 'name:' and 'root:'"
            )
        self.check_fields(top, MISSION_FIELDS, "the mission")
        for required in ("name", "root"):
            if required not in top:
                raise InvalidValueError(
                    top.pos, f"the mission has no {required!r}, expected fields: {', '.join(MISSION_FIELDS)}"
                )
        name = self.ident(top.required("name"), "the mission name")
        doc_node = top.get("doc")
        doc = None
        if doc_node is not None and not (isinstance(doc_node, YScalar) and doc_node.value is None):
            doc = self.string(doc_node, "doc")
        inputs = self.inputs(top.get("inputs"))
        outputs = self.outputs(top.get("outputs"))
        root = self.node(top.required("root"))
        return Mission(name, doc, inputs, outputs, root, self.file, self.source, top.pos)

    def type_name(self, node: YNode) -> ValueType:
        text = self.string(node, "type")
        try:
            return ValueType(text)
        except ValueError:
            names = [t.value for t in ValueType]
            raise InvalidValueError(
                node.pos, f"unknown type {shorten(text)}{suggest(text, names)}, expected one of: {', '.join(names)}"
            ) from None

    def inputs(self, node: YNode | None) -> tuple[InputSpec, ...]:
        if node is None or isinstance(node, YScalar) and node.value is None:
            return ()
        m = self.mapping(node, "inputs", "{category: {type: str, default: can}}")
        specs = []
        for key, spec in m.items:
            name = self.ident(key, "input name")
            if keyword.iskeyword(name):  # inputs are the parameters of the tree as an actor
                raise InvalidValueError(
                    key.pos, f"input name {name!r} is a Python keyword, expected a name a parameter can have"
                )
            if isinstance(spec, YScalar) and isinstance(spec.value, str):
                specs.append(InputSpec(name, self.type_name(spec), REQUIRED, None, key.pos))
                continue
            spec_map = self.mapping(spec, f"input {name!r}", "{type: float, default: 0.5}")
            self.check_fields(spec_map, ("type", "default", "doc"), f"input {name!r}")
            default = REQUIRED
            default_node = spec_map.get("default")
            if default_node is not None:
                default = plain(default_node)
            type_node = spec_map.get("type")
            if type_node is not None:
                vtype = self.type_name(type_node)
            elif default is not REQUIRED:
                vtype = ValueType.of(default)
            else:
                vtype = ValueType.ANY
            if default_node is not None and default is not None and not vtype.accepts(default):
                raise InvalidValueError(
                    default_node.pos,
                    f"default of input {name!r} is {_kind(default_node)}, expected a {vtype.value}",
                )
            doc_node = spec_map.get("doc")
            doc = self.string(doc_node, "doc") if doc_node is not None else None
            specs.append(InputSpec(name, vtype, default, doc, key.pos))
        return tuple(specs)

    def outputs(self, node: YNode | None) -> tuple[OutputSpec, ...]:
        if node is None or isinstance(node, YScalar) and node.value is None:
            return ()
        specs: list[OutputSpec] = []
        if isinstance(node, YSeq):
            seen: dict[str, Pos] = {}
            for item in node.items:
                name = self.ident(item, "output name")
                if name in seen:
                    raise InvalidValueError(
                        item.pos, f"output {name!r} listed twice (first at line {seen[name].line}), expected each once"
                    )
                seen[name] = item.pos
                specs.append(OutputSpec(name, ValueType.ANY, None, item.pos))
            return tuple(specs)
        if not isinstance(node, YMap):
            raise InvalidValueError(
                node.pos, f"outputs must be a list of keys, got {_kind(node)}; expected e.g. [grasp]"
            )
        for key, spec in node.items:
            name = self.ident(key, "output name")
            if isinstance(spec, YScalar) and isinstance(spec.value, str):
                specs.append(OutputSpec(name, self.type_name(spec), None, key.pos))
                continue
            spec_map = self.mapping(spec, f"output {name!r}", "{type: dict, doc: the grasp used}")
            self.check_fields(spec_map, ("type", "doc"), f"output {name!r}")
            type_node = spec_map.get("type")
            doc_node = spec_map.get("doc")
            specs.append(
                OutputSpec(
                    name,
                    self.type_name(type_node) if type_node is not None else ValueType.ANY,
                    self.string(doc_node, "doc") if doc_node is not None else None,
                    key.pos,
                )
            )
        return tuple(specs)

    # ------------------------------------------------------------ nodes

    def node(self, y: YNode) -> Node:
        if not isinstance(y, YMap):
            hint = ""
            if isinstance(y, YScalar) and isinstance(y.value, str) and _ACTOR_NAME.match(y.value):
                hint = f" (to call an actor write {{do: {y.value}}})"
            raise UnknownNodeError(
                y.pos, f"expected a node mapping such as {{do: actor}} or {{sequence: [...]}}, got {_kind(y)}{hint}"
            )
        types = [k for k, _ in y.items if k.raw in NODE_TYPES]
        if not types:
            others = [k for k, _ in y.items if k.raw != "name"]
            if others:
                key = others[0]
                raise UnknownNodeError(
                    key.pos,
                    f"unknown node type {shorten(key.raw)}{suggest(key.raw, NODE_TYPES)}, "
                    f"expected one of: {', '.join(NODE_TYPES)}",
                )
            raise UnknownNodeError(y.pos, f"node has no type, expected one of: {', '.join(NODE_TYPES)}")
        if len(types) > 1:
            raise UnknownNodeError(
                types[1].pos,
                f"node has two types {shorten(types[0].raw)} and {shorten(types[1].raw)}, "
                "expected exactly one per node (put several nodes in a sequence)",
            )
        kind = types[0].raw
        self.check_fields(y, (kind, "name", *_NODE_FIELDS.get(kind, ())), f"a {kind} node")
        common: dict[str, Any] = {
            "pos": y.pos,
            "field_pos": {k.raw: v.pos for k, v in y.items},
        }
        name_node = y.get("name")
        if name_node is not None:
            name = self.string(name_node, "name")
            if not name.strip() or "/" in name:
                raise InvalidValueError(
                    name_node.pos, f"name {shorten(name)} is not a valid node name, expected non-empty text without '/'"
                )
            common["name"] = name
        value = y.required(kind)
        if kind in _PLUGINS:
            return self.plugin(kind, y, value, common)
        if kind in _COMPOSITES:
            return self.composite(kind, value, common)
        if kind in _DECORATOR_FIELDS:
            return self.decorator(kind, value, common)
        if kind in _SIMPLE_DECORATORS:
            child_node = value
            if isinstance(value, YMap) and value.keys() == ["child"]:
                child_node = value.required("child")
            return _SIMPLE_DECORATORS[kind](child=self.node(child_node), **common)
        return getattr(self, "leaf_" + kind)(y, value, common)

    def children(self, kind: str, node: YNode) -> tuple[Node, ...]:
        if not isinstance(node, YSeq):
            raise InvalidValueError(
                node.pos, f"{kind} takes a list of child nodes, got {_kind(node)}; expected '- do: ...' items"
            )
        if not node.items:
            raise InvalidValueError(node.pos, f"{kind} has no children, expected at least one child node")
        children = tuple(self.node(item) for item in node.items)
        seen: dict[str, Pos] = {}
        for child in children:
            if child.name is None:
                continue
            if child.name in seen:
                raise InvalidValueError(
                    child.at("name"),
                    f"two children of this {kind} are named {child.name!r} (first at line {seen[child.name].line}), "
                    "expected distinct names among siblings",
                )
            seen[child.name] = child.at("name")
        return children

    def composite(self, kind: str, value: YNode, common: dict[str, Any]) -> Node:
        if kind == "recovery":
            return self.recovery(value, common)
        if kind in _BRANCHING:
            children = self.children(kind, value)
            if len(children) not in (2, 3):
                raise InvalidValueError(
                    value.pos,
                    f"{kind} has {len(children)} children, expected 2 or 3: the condition, what runs when it "
                    "succeeds and, optionally, what runs when it fails",
                )
            return _COMPOSITES[kind](children=children, **common)
        if kind != "parallel":
            return _COMPOSITES[kind](children=self.children(kind, value), **common)
        if isinstance(value, YSeq):
            return Parallel(children=self.children(kind, value), **common)
        m = self.mapping(value, "parallel", "{policy: success_on_one, children: [...]}")
        self.check_fields(m, ("policy", "children", "selected", "success_count", "failure_count"), "parallel")
        if "children" not in m:
            raise InvalidValueError(m.pos, "parallel has no 'children', expected a list of child nodes")
        children = self.children(kind, m.required("children"))
        if "success_count" in m or "failure_count" in m:
            return self.counted_parallel(m, children, common)
        policy = ParallelPolicy.SUCCESS_ON_ALL
        policy_pos = m.pos
        policy_node = m.get("policy")
        if policy_node is not None:
            policy_pos = policy_node.pos
            text = self.string(policy_node, "policy")
            try:
                policy = ParallelPolicy(text)
            except ValueError:
                names = [p.value for p in ParallelPolicy]
                raise InvalidValueError(
                    policy_node.pos,
                    f"unknown policy {shorten(text)}{suggest(text, names)}, expected one of: {', '.join(names)}",
                ) from None
        selected: list[str] = []
        selected_node = m.get("selected")
        if policy is ParallelPolicy.SUCCESS_ON_SELECTED:
            if selected_node is None:
                raise InvalidValueError(
                    policy_pos, "policy success_on_selected needs 'selected', expected a list of child names"
                )
            if not isinstance(selected_node, YSeq) or not selected_node.items:
                raise InvalidValueError(
                    selected_node.pos, f"selected must be a non-empty list of child names, got {_kind(selected_node)}"
                )
            names = [c.name for c in children if c.name is not None]
            for item in selected_node.items:
                text = self.string(item, "selected child")
                if text not in names:
                    raise InvalidValueError(
                        item.pos,
                        f"no child named {shorten(text)} in this parallel{suggest(text, names)}, "
                        f"expected one of the children's names: {', '.join(names) or '(give children a name:)'}",
                    )
                if text in selected:
                    raise InvalidValueError(item.pos, f"child {text!r} selected twice, expected each once")
                selected.append(text)
        elif selected_node is not None:
            raise InvalidValueError(
                selected_node.pos,
                f"'selected' only applies to policy success_on_selected, the policy is {policy.value}",
            )
        return Parallel(children=children, policy=policy, selected=tuple(selected), **common)

    def counted_parallel(self, m: YMap, children: tuple[Node, ...], common: dict[str, Any]) -> Node:
        for other in ("policy", "selected"):
            if other in m:
                raise InvalidValueError(
                    m.required(other).pos, f"parallel takes either {other!r} or success_count/failure_count, not both"
                )
        n = len(children)
        counts: dict[str, int] = {}
        for field_name in ("success_count", "failure_count"):
            node = m.get(field_name)
            if node is None:
                continue
            value = node.value if isinstance(node, YScalar) else None
            if isinstance(value, bool) or not isinstance(value, int) or value == 0 or not -n <= value <= n:
                raise InvalidValueError(
                    node.pos,
                    f"parallel {field_name} is {_kind(node)}, expected an integer from 1 to {n} (the number "
                    f"of children), or from -1 to -{n} to count from all of them (-1: all)",
                )
            counts[field_name] = value
        return Parallel(
            children=children,
            success_count=counts.get("success_count", -1),
            failure_count=counts.get("failure_count", 1),
            **common,
        )

    def recovery(self, value: YNode, common: dict[str, Any]) -> Node:
        example = "{retries: 2, children: [{do: follow_path}, {do: clear_costmap}]}"
        m = self.mapping(value, "recovery", example)
        self.check_fields(m, ("retries", "children"), "recovery")
        if "children" not in m:
            raise InvalidValueError(m.pos, f"recovery has no 'children', expected e.g. recovery: {example}")
        children = self.children("recovery", m.required("children"))
        if len(children) != 2:
            raise InvalidValueError(
                m.required("children").pos,
                f"recovery has {len(children)} children, expected 2: the action and its recovery",
            )
        common["field_pos"] = dict(common["field_pos"]) | {k.raw: v.pos for k, v in m.items}
        retries_node = m.get("retries")
        retries = 1 if retries_node is None else self.number(retries_node, "recovery retries", integer=True, minimum=0)
        return Recovery(children=children, retries=retries, **common)

    def decorator(self, kind: str, value: YNode, common: dict[str, Any]) -> Node:
        param = _DECORATOR_FIELDS[kind][0]
        example = _DECORATOR_EXAMPLES[kind]
        if kind == "run_once" and not (isinstance(value, YMap) and "child" in value):
            return RunOnce(child=self.node(value), **common)
        m = self.mapping(value, kind, example)
        self.check_fields(m, _DECORATOR_FIELDS[kind], kind)
        if "child" not in m:
            raise InvalidValueError(m.pos, f"{kind} has no 'child', expected e.g. {kind}: {example}")
        child = self.node(m.required("child"))
        common["field_pos"] = dict(common["field_pos"]) | {k.raw: v.pos for k, v in m.items}
        param_node = m.get(param)
        if kind == "repeat":
            times = (
                None
                if param_node is None
                else self.number(param_node, "repeat times", integer=True, minimum=1, words={"forever": None})
            )
            return Repeat(child=child, times=times, **common)
        if kind == "run_once":
            then = RunOnceThen.SAME
            if param_node is not None:
                text = self.string(param_node, "run_once then")
                names = [t.value for t in RunOnceThen]
                if text not in names:
                    raise InvalidValueError(
                        param_node.pos,
                        f"run_once then is {shorten(text)}{suggest(text, names)}, expected one of: {', '.join(names)}",
                    )
                then = RunOnceThen(text)
            return RunOnce(child=child, then=then, **common)
        if param_node is None:
            raise InvalidValueError(m.pos, f"{kind} has no {param!r}, expected e.g. {kind}: {example}")
        if kind == "retry":
            times = self.number(param_node, "retry times", integer=True, minimum=1, words={"forever": None})
            return Retry(child=child, times=times, **common)
        if kind == "rate_controller":
            hz = self.number(param_node, "rate_controller hz", integer=False, minimum=0)
            if hz == 0:
                raise InvalidValueError(param_node.pos, "rate_controller hz is 0, expected a number > 0")
            return RateController(child=child, hz=hz, **common)
        seconds = self.number(param_node, "timeout seconds", integer=False, minimum=0)
        if seconds == 0:
            raise InvalidValueError(param_node.pos, "timeout seconds is 0, expected a number > 0")
        return Timeout(child=child, seconds=seconds, **common)

    def plugin(self, kind: str, y: YMap, value: YNode, common: dict[str, Any]) -> Node:
        """``control: Name`` with ``children:``, or ``decorator: Name`` with ``child:``;
        ``with:`` gives the input ports, ``out:`` maps output ports to keys. Whether the
        name, ports and child count fit the plugin is checked in ``_validate``."""
        name = self.string(value, kind)
        if not _IDENT.match(name):
            raise InvalidValueError(
                value.pos,
                f"{kind} {shorten(name)} is not a node name, expected the name a "
                f"plugin is registered under, e.g. RoundRobin",
            )
        ports: dict[str, Any] = {}
        port_pos: dict[str, Pos] = {}
        with_node = y.get("with")
        if with_node is not None and not (isinstance(with_node, YScalar) and with_node.value is None):
            for key, val in self.mapping(with_node, "with", '{distance: 1.0, goal: "{goal}"}').items:
                port = self.ident(key, "port name")
                ports[port] = self.value(val)
                port_pos[port] = val.pos
        outs: dict[str, str] = {}
        out_pos: dict[str, Pos] = {}
        out_node = y.get("out")
        if out_node is not None:
            for key, val in self.mapping(out_node, f"{kind} out", "{output_goal: goal}").items:
                port = self.ident(key, "output port name")
                outs[port] = self.ident(val, f"the key of output port {port!r}")
                out_pos[port] = val.pos
        fields = dict(plugin=name, ports=ports, outs=outs, port_pos=port_pos, out_pos=out_pos, **common)
        if kind == "control":
            if "children" not in y:
                raise InvalidValueError(y.pos, f"control {name!r} has no 'children', expected a list of child nodes")
            return PluginControl(children=self.children(f"control {name}", y.required("children")), **fields)
        if "child" not in y:
            raise InvalidValueError(y.pos, f"decorator {name!r} has no 'child', expected e.g. child: {{do: plan}}")
        return PluginDecorator(child=self.node(y.required("child")), **fields)

    # ------------------------------------------------------------ leaves

    def leaf_do(self, y: YMap, value: YNode, common: dict[str, Any], node_class: type[Do] = Do) -> Node:
        kind = node_class.kind
        actor = self.string(value, kind)
        if not _ACTOR_NAME.match(actor):
            raise InvalidValueError(
                value.pos,
                f"{kind} {shorten(actor)} is not an actor name, expected e.g. navigate or robot.navigation.goto",
            )
        args: tuple[Any, ...] = ()
        kwargs: dict[str, Any] = {}
        arg_pos: dict[str, Pos] = {}
        arg_key_pos: dict[str, Pos] = {}
        with_node = y.get("with")
        if isinstance(with_node, YSeq):
            args = tuple(self.value(item) for item in with_node.items)
            arg_pos = {str(i): item.pos for i, item in enumerate(with_node.items)}
        elif isinstance(with_node, YMap):
            for key, val in with_node.items:
                name = self.ident(key, "argument name")
                kwargs[name] = self.value(val)
                arg_pos[name] = val.pos
                arg_key_pos[name] = key.pos
        elif with_node is not None and not (isinstance(with_node, YScalar) and with_node.value is None):
            raise InvalidValueError(
                with_node.pos,
                f'with must be a mapping of arguments, got {_kind(with_node)}; expected e.g. {{target: "{{found}}"}}',
            )
        out_node = y.get("out")
        out = self.ident(out_node, "out key") if out_node is not None else None
        return node_class(
            actor=actor, args=args, kwargs=kwargs, out=out, arg_pos=arg_pos, arg_key_pos=arg_key_pos, **common
        )

    def leaf_condition(self, y: YMap, value: YNode, common: dict[str, Any]) -> Node:
        return self.leaf_do(y, value, common, Condition)

    def leaf_set(self, y: YMap, value: YNode, common: dict[str, Any]) -> Node:
        m = self.mapping(value, "set", '{attempts: 0, target: "{found}"}')
        if not m.items:
            raise InvalidValueError(m.pos, "set has nothing to write, expected at least one key: value")
        values = {}
        key_pos = {}
        for key, val in m.items:
            name = self.ident(key, "blackboard key")
            values[name] = self.value(val)
            key_pos[name] = key.pos
        return SetValues(values=values, key_pos=key_pos, **common)

    def leaf_check(self, y: YMap, value: YNode, common: dict[str, Any]) -> Node:
        if not isinstance(value, YScalar) or value.value is None:
            raise InvalidValueError(
                value.pos, f"check takes an expression, got {_kind(value)}; expected e.g. check: battery > 0.2"
            )
        source = value.raw
        try:
            expr = parse_expression(source)
        except ExprSyntaxError as exc:
            raise CheckExpressionError(value.pos_at(exc.offset), f"bad check expression: {exc.message}") from None
        key_pos = tuple((key.name, value.pos_at(key.offset)) for key in keys_of(expr))
        return Check(source=source, expr=expr, key_pos=key_pos, **common)

    def leaf_wait(self, y: YMap, value: YNode, common: dict[str, Any]) -> Node:
        return Wait(seconds=self.number(value, "wait seconds", integer=False, minimum=0), **common)

    def leaf_behaviour(self, y: YMap, value: YNode, common: dict[str, Any]) -> Node:
        name = self.string(value, "behaviour")
        if not _ACTOR_NAME.match(name):
            raise InvalidValueError(
                value.pos, f"behaviour {shorten(name)} is not a registered name, expected e.g. CheckBattery"
            )
        kwargs: dict[str, Any] = {}
        arg_pos: dict[str, Pos] = {}
        with_node = y.get("with")
        if with_node is not None:
            m = self.mapping(with_node, "with", "{threshold: 0.2}")
            for key, val in m.items:
                arg = self.ident(key, "argument name")
                kwargs[arg] = self.value(val)
                arg_pos[arg] = val.pos
        writes: tuple[str, ...] = ()
        writes_node = y.get("writes")
        if writes_node is not None:
            items = writes_node.items if isinstance(writes_node, YSeq) else (writes_node,)
            writes = tuple(self.ident(item, "written key") for item in items)
        return UseBehaviour(behaviour=name, kwargs=kwargs, writes=writes, arg_pos=arg_pos, **common)


def parse_mission(source: str, file: str = "<mission>") -> Mission:
    """Parse mission text into the typed model, checking everything the file alone decides.

    Raises:
        MissionError: the first problem found, as ``file:line:column: message``.
        LimitError: the text is longer than MAX_MISSION_SIZE, or goes past a limit of
            the YAML reader or the check: language.
    """
    if len(source) > MAX_MISSION_SIZE:
        raise LimitError(Pos(file, 1, 1), f"mission longer than {MAX_MISSION_SIZE} characters, expected a smaller file")
    return _Parser(file, source).mission()


def _read_bytes(path: str | Path, file: str) -> bytes:
    # Read at most one byte past the limit: the file may be /dev/zero or still growing.
    try:
        with open(path, "rb") as stream:
            data = stream.read(MAX_MISSION_SIZE + 1)
    except (OSError, ValueError) as exc:  # ValueError: a NUL in the path
        raise MissionError(
            Pos(file, 1, 1), f"cannot read mission file: {getattr(exc, 'strerror', None) or exc}"
        ) from None
    if len(data) > MAX_MISSION_SIZE:
        raise LimitError(Pos(file, 1, 1), f"file larger than {MAX_MISSION_SIZE} bytes, expected a mission file")
    return data


def _decode(data: bytes, file: str) -> str:
    if data.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        raise MissionSyntaxError(Pos(file, 1, 1), "file is UTF-16 text, expected UTF-8")
    try:
        return data.decode("utf-8-sig")  # a UTF-8 BOM is dropped, so columns on line 1 stay right
    except UnicodeDecodeError as exc:
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        line = data.count(b"\n", 0, exc.start) + 1
        column = len(data[line_start : exc.start].decode("utf-8-sig" if line_start == 0 else "utf-8", "replace")) + 1
        raise MissionSyntaxError(
            Pos(file, line, column), f"file is not UTF-8 text (byte 0x{data[exc.start]:02X}), expected a YAML mission"
        ) from None


def read_mission(path: str | Path) -> Mission:
    """Read and parse a mission file (see :func:`parse_mission`).

    Raises:
        MissionError: unreadable file, or a problem in it.
        LimitError: a file larger than MAX_MISSION_SIZE bytes.
    """
    file = str(path)
    return parse_mission(_decode(_read_bytes(path, file), file), file)
