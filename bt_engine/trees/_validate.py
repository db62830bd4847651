"""Load-time validation of a parsed mission against the actors, behaviours and trees it
uses: names, signatures, blackboard data flow and subtree cycles.

The validator takes the actor resolver as a parameter, so tests can pass a tiny fake
one (see :mod:`bt_engine.trees.testing`) and the engine passes ``rt.root.resolve``.
"""

from __future__ import annotations

import inspect
import typing
from collections.abc import Collection, Mapping
from typing import Any, Callable, Iterator, Protocol

from ._errors import (
    ActorbtError,
    ArgumentMismatchError,
    InvalidValueError,
    LimitError,
    MissionError,
    Pos,
    SubtreeCycleError,
    UnknownBehaviourError,
    UnknownBlackboardKeyError,
    UnknownNodeError,
    UnresolvedActorError,
    out_of_range,
    shorten,
)
from ._model import (
    Check,
    Do,
    Mission,
    PluginControl,
    PluginNode,
    RateController,
    Recovery,
    Ref,
    Repeat,
    Retry,
    SetValues,
    Timeout,
    UseBehaviour,
    ValueType,
    Wait,
    refs_in,
    walk,
)
from ._parse import suggest
from ._plugins import InputPort, PluginSpec

__all__ = [
    "MAX_ERRORS",
    "ActorInfo",
    "Resolver",
    "annotation_text",
    "annotation_type",
    "format_signature",
    "validate_mission",
]


class ActorInfo(Protocol):
    """What the validator needs to know about an actor (``rt.root.resolve(name)``)."""

    @property
    def path(self) -> str: ...

    @property
    def signature(self) -> inspect.Signature: ...

    @property
    def is_tree(self) -> bool: ...


#: ``name -> ActorInfo``; raises an error with ``.suggestions`` for unknown names.
Resolver = Callable[[str], ActorInfo]

#: Validation of one mission stops after this many problems: nobody reads more, and
#: each may search for close matches (a megabyte of bad keys would take hours).
MAX_ERRORS = 100

_BUILTIN_TYPES = {
    str: ValueType.STR,
    int: ValueType.INT,
    float: ValueType.FLOAT,
    bool: ValueType.BOOL,
    list: ValueType.LIST,
    tuple: ValueType.LIST,
    dict: ValueType.DICT,
}
_TYPE_NAMES = {
    "str": ValueType.STR,
    "int": ValueType.INT,
    "float": ValueType.FLOAT,
    "bool": ValueType.BOOL,
    "list": ValueType.LIST,
    "dict": ValueType.DICT,
}


def _choices(info: Any, name: str) -> list | None:
    """The values a ``Literal[...]`` parameter allows, from the actor's tool schema
    (the actor index keeps it; an actor reference has its catalog entry made)."""
    tool = getattr(info, "tool", None)
    if tool is None:
        from ..catalog import tool_schema

        tool = tool_schema(info)
    schema = tool.get("parameters", {}).get("properties", {}).get(name, {})
    return schema.get("enum") or schema.get("items", {}).get("enum")


def annotation_type(annotation: Any) -> ValueType | None:
    """The :class:`ValueType` a parameter annotation demands, or ``None`` if it cannot
    be checked statically (no annotation, unions, classes of our own...)."""
    if annotation is inspect.Parameter.empty or annotation is Any:
        return None
    if isinstance(annotation, str):
        return _TYPE_NAMES.get(annotation.split("[", 1)[0].strip())
    if annotation in _BUILTIN_TYPES:
        return _BUILTIN_TYPES[annotation]
    origin = typing.get_origin(annotation)
    if origin in (list, tuple, dict):
        return _BUILTIN_TYPES[origin]
    return None


def annotation_text(annotation: Any) -> str:
    """A type annotation as a reader writes it (``int``, ``list[str]``, ``dict | None``)."""
    if isinstance(annotation, str):
        return annotation
    if isinstance(annotation, type):
        return annotation.__name__
    return repr(annotation).replace("typing.", "")


def format_signature(name: str, sig: inspect.Signature) -> str:
    """``name(a: int, b: str = 'x', *, c) -> bool``, without the quotes that postponed
    (string) annotations get from ``str(signature)``."""
    params = list(sig.parameters.values())
    last_positional_only = max((i for i, p in enumerate(params) if p.kind is p.POSITIONAL_ONLY), default=-1)
    parts: list[str] = []
    star_done = False
    for i, p in enumerate(params):
        if p.kind is p.KEYWORD_ONLY and not star_done:
            parts.append("*")
        star_done = star_done or p.kind in (p.VAR_POSITIONAL, p.KEYWORD_ONLY)
        text = ("*" if p.kind is p.VAR_POSITIONAL else "**" if p.kind is p.VAR_KEYWORD else "") + p.name
        if p.annotation is not p.empty:
            text += f": {annotation_text(p.annotation)}"
            if p.default is not p.empty:
                text += f" = {p.default!r}"
        elif p.default is not p.empty:
            text += f"={p.default!r}"
        parts.append(text)
        if i == last_positional_only:
            parts.append("/")
    result = f"{name}({', '.join(parts)})"
    if sig.return_annotation is not sig.empty:
        result += f" -> {annotation_text(sig.return_annotation)}"
    return result


def _a(vtype: ValueType) -> str:
    """'an int', 'a str'..."""
    return ("an " if vtype.value[0] in "aeiou" else "a ") + vtype.value


def _fits(expected: ValueType, actual: ValueType) -> bool:
    if ValueType.ANY in (expected, actual) or expected is actual:
        return True
    return expected is ValueType.FLOAT and actual is ValueType.INT


class _Validator:
    def __init__(
        self,
        mission: Mission,
        resolver: Resolver | None,
        behaviours: Collection[str] | None,
        trees: Mapping[str, Mission] | None,
        nodes: Mapping[str, PluginSpec] | None = None,
    ) -> None:
        self.mission = mission
        self.nodes = nodes
        self.resolver = resolver
        self.behaviours = behaviours
        self.trees = trees
        self.errors: list[MissionError] = []
        self.resolved: dict[int, ActorInfo] = {}
        self.key_types: dict[str, ValueType] = {}  # every key written, with its static type

    @property
    def full(self) -> bool:
        return len(self.errors) >= MAX_ERRORS

    def run(self) -> list[MissionError]:
        self.resolve_actors()
        self.collect_writers()
        for node in walk(self.mission.root):
            if self.full:
                break
            if isinstance(node, Do):
                self.check_do(node)
            elif isinstance(node, SetValues):
                for value in node.values.values():
                    self.check_refs(value)
            elif isinstance(node, Check):
                for key, pos in node.key_pos:
                    self.check_key(key, pos)
            elif isinstance(node, Wait):
                self.check_number(node.seconds, ValueType.FLOAT, "wait seconds")
            elif isinstance(node, Timeout):
                self.check_number(node.seconds, ValueType.FLOAT, "timeout seconds")
            elif isinstance(node, (Retry, Repeat)):
                self.check_number(node.times, ValueType.INT, f"{node.kind} times")
            elif isinstance(node, Recovery):
                self.check_number(node.retries, ValueType.INT, "recovery retries")
            elif isinstance(node, RateController):
                self.check_number(node.hz, ValueType.FLOAT, "rate_controller hz")
            elif isinstance(node, UseBehaviour):
                self.check_behaviour(node)
            elif isinstance(node, PluginNode):
                self.check_plugin(node)
        for spec in self.mission.outputs:
            if spec.name not in self.key_types and not self.full:
                self.errors.append(
                    UnknownBlackboardKeyError(
                        spec.pos,
                        f"output {spec.name!r} is never written, "
                        "expected a key set by out:, set: or writes: in the tree"
                        f"{suggest(spec.name, self.key_types)}",
                    )
                )
        self.check_cycles()
        errors = sorted(self.errors, key=lambda e: (e.pos.line, e.pos.column))
        if not self.full:
            return errors
        errors = errors[:MAX_ERRORS]
        return [
            *errors,
            LimitError(
                errors[-1].pos, f"more than {MAX_ERRORS} problems in this mission, stopped checking (fix these first)"
            ),
        ]

    # ------------------------------------------------------------ actors

    def resolve_actors(self) -> None:
        if self.resolver is None:
            return
        for node in walk(self.mission.root):
            if self.full:
                break
            if not isinstance(node, Do):
                continue
            try:
                self.resolved[id(node)] = self.resolver(node.actor)
            except (LookupError, ActorbtError) as exc:
                suggestions = getattr(exc, "suggestions", None)
                if suggestions is not None:
                    hint = f" (did you mean {' or '.join(repr(s) for s in suggestions)}?)" if suggestions else ""
                    message = f"unknown actor {shorten(node.actor)}{hint}, expected a registered actor or tree name"
                else:
                    message = f"cannot resolve actor {shorten(node.actor)}: {exc}"
                self.errors.append(UnresolvedActorError(node.at(node.kind), message))

    def check_do(self, node: Do) -> None:
        for value in (*node.args, *node.kwargs.values()):
            self.check_refs(value)
        info = self.resolved.get(id(node))
        if info is None:
            return
        sig = info.signature
        shown = format_signature(node.actor, sig)
        params = sig.parameters
        var_kw = any(p.kind is p.VAR_KEYWORD for p in params.values())
        for name in node.kwargs:
            param = params.get(name)
            if (param is None and not var_kw) or (
                param is not None and param.kind in (param.POSITIONAL_ONLY, param.VAR_POSITIONAL, param.VAR_KEYWORD)
            ):
                names = [p.name for p in params.values() if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]
                self.errors.append(
                    ArgumentMismatchError(
                        node.arg_key_pos.get(name, node.at("with")),
                        f"actor {node.actor!r} has no parameter {name!r}{suggest(name, names)}, expected {shown}",
                    )
                )
                return
        try:
            bound = sig.bind(*node.args, **node.kwargs)
        except TypeError as exc:
            self.errors.append(
                ArgumentMismatchError(
                    node.at("with") if "with" in node.field_pos else node.at(node.kind),
                    f"arguments do not fit actor {node.actor!r}: {exc}, expected {shown}",
                )
            )
            return
        limits = getattr(getattr(info, "safety", None), "limits", None) or {}
        for name, value in bound.arguments.items():
            param = params[name]
            pos = node.arg_pos.get(name)
            if pos is None:
                index = list(params).index(name)
                pos = node.arg_pos.get(str(index), node.at("with"))
            what = f"argument {name!r} of actor {node.actor!r}"
            if param.kind is param.VAR_POSITIONAL:  # each value where it is written
                first = list(params).index(name)
                placed = [(v, node.arg_pos.get(str(first + k), pos)) for k, v in enumerate(value)]
            else:
                placed = [(value, pos)]
            if name in limits:
                self.check_limit(placed, limits[name], what)
            if "Literal" in str(param.annotation) and param.kind is not param.VAR_KEYWORD:
                self.check_choice(placed, _choices(info, name), what)
            if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
                continue
            expected = annotation_type(param.annotation)
            if expected is None:
                continue
            self.check_type(value, expected, pos, f"argument {name!r} of actor {node.actor!r}")

    def check_limit(self, placed: list[tuple[Any, Pos]], limit: tuple, what: str) -> None:
        """A literal number outside the range the actor declares (``@actor(limits=...)``,
        the catalog's minimum/maximum) is an error, as MCP refuses it; a reference is
        checked when its node runs (``_behaviours``)."""
        for value, pos in placed:
            problem = out_of_range(what, value, limit)
            if problem is not None:
                self.errors.append(ArgumentMismatchError(pos, problem))

    def check_choice(self, placed: list[tuple[Any, Pos]], choices: list | None, what: str) -> None:
        """A literal value that is not one of a ``Literal[...]`` parameter's choices."""
        if not choices:
            return
        for value, pos in placed:
            if not any(refs_in(value)) and value not in choices:
                self.errors.append(
                    ArgumentMismatchError(
                        pos,
                        f"{what} is {shorten(value)}, expected one of {', '.join(repr(c) for c in choices)}"
                        f"{suggest(str(value), [str(c) for c in choices])}",
                    )
                )

    def check_type(self, value: Any, expected: ValueType, pos: Pos, what: str) -> None:
        if isinstance(value, Ref):
            actual = self.ref_type(value)
            if not _fits(expected, actual):
                self.errors.append(
                    ArgumentMismatchError(value.pos, f"{what} expects {_a(expected)}, but {value} holds {_a(actual)}")
                )
        elif not any(refs_in(value)) and not expected.accepts(value):
            self.errors.append(
                ArgumentMismatchError(
                    pos, f"{what} expects {_a(expected)}, got {type(value).__name__} {shorten(value)}"
                )
            )

    # ------------------------------------------------------------ blackboard

    def collect_writers(self) -> None:
        types: dict[str, set[ValueType]] = {}

        def wrote(key: str, vtype: ValueType) -> None:
            types.setdefault(key, set()).add(vtype)

        for spec in self.mission.inputs:
            wrote(spec.name, spec.type)
        for node in walk(self.mission.root):
            if isinstance(node, Do) and node.out is not None:
                info = self.resolved.get(id(node))
                vtype = ValueType.ANY
                if info is not None:
                    vtype = (
                        ValueType.DICT
                        if info.is_tree
                        else (annotation_type(info.signature.return_annotation) or ValueType.ANY)
                    )
                wrote(node.out, vtype)
            elif isinstance(node, SetValues):
                for key, value in node.values.items():
                    wrote(key, ValueType.ANY if list(refs_in(value)) else ValueType.of(value))
            elif isinstance(node, UseBehaviour):
                for key in node.writes:
                    wrote(key, ValueType.ANY)
            elif isinstance(node, PluginNode):
                plugin = self.nodes.get(node.plugin) if self.nodes is not None else None
                for port, key in node.outs.items():
                    declared = plugin.outputs.get(port) if plugin is not None else None
                    wrote(
                        key, annotation_type(declared.type) or ValueType.ANY if declared is not None else ValueType.ANY
                    )
        self.key_types = {k: (next(iter(v)) if len(v) == 1 else ValueType.ANY) for k, v in types.items()}

    def ref_type(self, ref: Ref) -> ValueType:
        if ref.fields:
            return ValueType.ANY
        return self.key_types.get(ref.key, ValueType.ANY)

    def check_key(self, key: str, pos: Pos) -> bool:
        if key in self.key_types:
            return True
        self.errors.append(
            UnknownBlackboardKeyError(
                pos,
                f"blackboard key {key!r} is never written{suggest(key, self.key_types)}, "
                "expected an input or a key set by out:, set: or writes:",
            )
        )
        return False

    def check_refs(self, value: Any) -> None:
        for ref in refs_in(value):
            self.check_key(ref.key, ref.pos)

    def check_number(self, value: Any, expected: ValueType, what: str) -> None:
        if isinstance(value, Ref) and self.check_key(value.key, value.pos):
            actual = self.ref_type(value)
            if not _fits(expected, actual):
                self.errors.append(
                    InvalidValueError(
                        value.pos,
                        f"{what} {value} holds {_a(actual)}, "
                        f"expected {'an int' if expected is ValueType.INT else 'a number'}",
                    )
                )

    # ------------------------------------------------------------ behaviours and trees

    def check_behaviour(self, node: UseBehaviour) -> None:
        inputs = {spec.name for spec in self.mission.inputs}
        for value in node.kwargs.values():
            for ref in refs_in(value):
                # A behaviour is built when the run starts, before anything else is written.
                if ref.key not in inputs:
                    self.errors.append(
                        UnknownBlackboardKeyError(
                            ref.pos,
                            f"behaviour arguments are fixed when the tree starts, so {ref} must name an input, "
                            f"expected one of: {', '.join(sorted(inputs)) or '(no inputs declared)'}",
                        )
                    )
        if self.behaviours is None or node.behaviour in self.behaviours:
            return
        known = sorted(self.behaviours)
        self.errors.append(
            UnknownBehaviourError(
                node.at("behaviour"),
                f"unknown behaviour {node.behaviour!r}{suggest(node.behaviour, known)}, "
                f"expected a registered behaviour: {', '.join(known) or '(none registered)'}",
            )
        )

    def check_plugin(self, node: PluginNode) -> None:
        """A control or decorator written in Python: its name, child count, ports (names
        and literal types) and the actors its ports name, against its spec."""
        for value in node.ports.values():
            self.check_refs(value)
        if self.nodes is None:
            return
        spec = self.nodes.get(node.plugin)
        if spec is None:
            known = sorted(n for n, s in self.nodes.items() if s.kind == node.kind)
            self.errors.append(
                UnknownNodeError(
                    node.at(node.kind),
                    f"unknown {node.kind} {node.plugin!r}{suggest(node.plugin, known)}, expected a registered "
                    f"{node.kind} node: {', '.join(known) or '(none registered)'}",
                )
            )
            return
        if spec.kind != node.kind:
            field = "children: [...]" if spec.kind == "control" else "child: {...}"
            self.errors.append(
                InvalidValueError(
                    node.at(node.kind),
                    f"{node.plugin!r} is a {spec.kind} node, expected {spec.kind}: {node.plugin} with {field}",
                )
            )
            return
        if isinstance(node, PluginControl):
            lo, hi = spec.child_count
            n = len(node.children)
            if n < lo or hi is not None and n > hi:
                wanted = f"{lo}" if lo == hi else f"{lo} to {hi}" if hi is not None else f"at least {lo}"
                self.errors.append(
                    InvalidValueError(
                        node.at("children"), f"control {node.plugin!r} has {n} children, expected {wanted}"
                    )
                )
        inputs = spec.inputs
        for name, value in node.ports.items():
            port = spec.ports.get(name)
            if not isinstance(port, InputPort):
                what = (
                    "is an output port, expected it under out:"
                    if port is not None
                    else f"is not a port of it{suggest(name, inputs)}, expected one of: {', '.join(inputs) or '(none)'}"
                )
                self.errors.append(
                    ArgumentMismatchError(
                        node.port_pos.get(name, node.at("with")), f"{node.kind} {node.plugin!r}: {name!r} {what}"
                    )
                )
                continue
            expected = annotation_type(port.type)
            if expected is not None:
                self.check_type(
                    value,
                    expected,
                    node.port_pos.get(name, node.at("with")),
                    f"port {name!r} of {node.kind} {node.plugin!r}",
                )
            if port.actor and isinstance(value, str) and self.resolver is not None:
                self.check_named_actor(value, node.port_pos.get(name, node.at("with")))
        outputs = spec.outputs
        for name in node.outs:
            if name not in outputs:
                self.errors.append(
                    ArgumentMismatchError(
                        node.out_pos.get(name, node.at("out")),
                        f"{node.kind} {node.plugin!r} has no output port {name!r}{suggest(name, outputs)}, "
                        f"expected one of: {', '.join(outputs) or '(none)'}",
                    )
                )

    def check_named_actor(self, name: str, pos: Pos) -> None:
        """An actor a plugin's port names, resolved as a ``do:`` target is."""
        assert self.resolver is not None
        try:
            self.resolver(name)
        except (LookupError, ActorbtError) as exc:
            suggestions = getattr(exc, "suggestions", None) or []
            hint = f" (did you mean {' or '.join(repr(s) for s in suggestions)}?)" if suggestions else ""
            self.errors.append(
                UnresolvedActorError(
                    pos, f"unknown actor {shorten(name)}{hint}, expected a registered actor or tree name"
                )
            )

    def tree_calls(self, mission: Mission) -> Iterator[tuple[str, Do]]:
        assert self.trees is not None
        for node in walk(mission.root):
            if isinstance(node, Do) and node.actor in self.trees:
                yield node.actor, node

    def path_back(self, callee: str) -> list[str] | None:
        """Trees ``callee -> ... -> this mission`` through ``do:`` calls, if there is a path.

        Depth first with an explicit stack: a folder may chain more trees than Python
        may recurse.
        """
        assert self.trees is not None
        start = self.mission.name
        came_from: dict[str, str | None] = {callee: None}
        stack = [callee]
        while stack:
            name = stack.pop()
            if name == start:
                path = [name]
                while (previous := came_from[path[-1]]) is not None:
                    path.append(previous)
                return path[::-1]
            if name not in self.trees:
                continue
            calls = [c for c, _ in self.tree_calls(self.trees[name]) if c not in came_from]
            for next_name in reversed(calls):  # reversed: the first call is explored first
                came_from[next_name] = name
                stack.append(next_name)
        return None

    def check_cycles(self) -> None:
        if self.trees is None:
            return
        start = self.mission.name
        for callee, node in self.tree_calls(self.mission):
            if self.full:
                break
            cycle = self.path_back(callee)
            if cycle is not None:
                self.errors.append(
                    SubtreeCycleError(
                        node.at(node.kind),
                        f"subtree cycle {' -> '.join([start, *cycle])}, expected trees that do not call "
                        "themselves directly or through other trees",
                    )
                )


def validate_mission(
    mission: Mission,
    resolver: Resolver | None = None,
    *,
    behaviours: Collection[str] | None = None,
    trees: Mapping[str, Mission] | None = None,
    nodes: Mapping[str, PluginSpec] | None = None,
) -> list[MissionError]:
    """Every load-time problem of a parsed mission, sorted by position (empty if none).

    Args:
        mission: from :func:`parse_mission`.
        resolver: ``name -> ActorInfo`` for ``do:`` targets; ``None`` skips actor checks.
        behaviours: names accepted by ``behaviour:``; ``None`` skips that check.
        trees: missions by name, to follow ``do:`` calls between trees for cycles.
        nodes: plugin controls and decorators by name; ``None`` skips that check.
    """
    return _Validator(mission, resolver, behaviours, trees, nodes).run()
