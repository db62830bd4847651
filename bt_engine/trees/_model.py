"""The typed mission model: what a mission file means, independent of YAML and py_trees.

The parser (``_parse``) builds it, the validator (``_validate``) checks it against the
actors, and the builder turns it into a py_trees tree. Every node keeps its position so
that any later error can still point at ``file:line:column``.
"""

from __future__ import annotations

import enum
import hashlib
import inspect
from dataclasses import dataclass, field
from typing import Any, Callable, ClassVar, Iterator, Mapping, Union

import yaml

from ._errors import InputError, Pos
from ._expr import Expr, read_path

__all__ = [
    "REQUIRED",
    "Check",
    "Condition",
    "Composite",
    "Decorator",
    "Do",
    "ForceFailure",
    "ForceSuccess",
    "IfThenElse",
    "InputSpec",
    "Invert",
    "Mission",
    "Node",
    "OutputSpec",
    "Parallel",
    "ParallelPolicy",
    "PipelineSequence",
    "PluginControl",
    "PluginDecorator",
    "PluginNode",
    "RateController",
    "ReactiveSelector",
    "ReactiveSequence",
    "Recovery",
    "Ref",
    "Repeat",
    "ResumeSequence",
    "Retry",
    "RunOnce",
    "RunOnceThen",
    "Selector",
    "Sequence",
    "SetValues",
    "Timeout",
    "UseBehaviour",
    "ValueType",
    "Wait",
    "WhileDoElse",
    "children_of",
    "refs_in",
    "resolve_value",
    "walk",
]


class _Required:
    """Marker: an input without a default."""

    def __repr__(self) -> str:
        return "REQUIRED"


REQUIRED: Any = _Required()


class ValueType(enum.Enum):
    """Type of a tree input or output, as written in ``type:``."""

    STR = "str"
    """Text."""
    INT = "int"
    """An integer (booleans are not integers here)."""
    FLOAT = "float"
    """A number; integers are accepted and kept as they are."""
    BOOL = "bool"
    """``true`` or ``false``."""
    LIST = "list"
    """A YAML sequence / Python list or tuple."""
    DICT = "dict"
    """A YAML mapping / Python dict."""
    ANY = "any"
    """Anything, unchecked."""

    @property
    def python_type(self) -> Any:
        """The annotation used in a tree's actor signature."""
        return {"str": str, "int": int, "float": float, "bool": bool, "list": list, "dict": dict}.get(
            self.value, inspect.Parameter.empty
        )

    def accepts(self, value: Any) -> bool:
        """Whether ``value`` is of this type."""
        if self is ValueType.ANY:
            return True
        if self is ValueType.BOOL:
            return isinstance(value, bool)
        if isinstance(value, bool):
            return False
        return isinstance(value, _PYTHON_TYPES[self])

    def coerce(self, text: str) -> Any:
        """Parse a command-line string (``--arg k=v``) into a value of this type.

        Raises:
            ValueError: the text is not a value of this type.
        """
        if self is ValueType.STR:
            return text
        if self is ValueType.BOOL:
            lowered = text.strip().lower()
            if lowered in ("true", "yes", "on", "1"):
                return True
            if lowered in ("false", "no", "off", "0"):
                return False
            raise ValueError(f"{text!r} is not a bool, expected true or false")
        if self is ValueType.INT:
            try:
                return int(text)
            except ValueError:
                raise ValueError(f"{text!r} is not an int") from None
        if self is ValueType.FLOAT:
            try:
                return float(text)
            except ValueError:
                raise ValueError(f"{text!r} is not a float") from None
        try:
            value = yaml.safe_load(text)
        except yaml.YAMLError:
            raise ValueError(f"{text!r} is not valid YAML") from None
        if not self.accepts(value):
            raise ValueError(f"{text!r} is not a {self.value}")
        return value

    @staticmethod
    def of(value: Any) -> ValueType:
        """The narrowest type of a literal value."""
        for t in (ValueType.BOOL, ValueType.INT, ValueType.FLOAT, ValueType.STR, ValueType.LIST, ValueType.DICT):
            if t.accepts(value):
                return t
        return ValueType.ANY


_PYTHON_TYPES: dict[ValueType, tuple[type, ...]] = {
    ValueType.STR: (str,),
    ValueType.INT: (int,),
    ValueType.FLOAT: (int, float),
    ValueType.LIST: (list, tuple),
    ValueType.DICT: (dict,),
}


@dataclass(frozen=True)
class Ref:
    """A typed blackboard reference, written as a whole string ``"{key}"`` or
    ``"{key.field.field}"``. At run time it is replaced by the value itself (not its text).
    """

    key: str
    fields: tuple[str, ...]
    pos: Pos

    @property
    def dotted(self) -> str:
        return ".".join((self.key, *self.fields))

    def __str__(self) -> str:
        return "{" + self.dotted + "}"

    def read(self, lookup: Callable[[str], Any]) -> Any:
        """The referenced value; ``lookup`` raises KeyError for unset keys.

        Raises:
            KeyError: the key is unset or a field is missing; the message names which.
        """
        return read_path(lookup, self.key, self.fields)


def refs_in(value: Any) -> Iterator[Ref]:
    """Every :class:`Ref` inside a (nested) value."""
    if isinstance(value, Ref):
        yield value
    elif isinstance(value, dict):
        for item in value.values():
            yield from refs_in(item)
    elif isinstance(value, (list, tuple)):
        for item in value:
            yield from refs_in(item)


def resolve_value(value: Any, lookup: Callable[[str], Any]) -> Any:
    """``value`` with every :class:`Ref` replaced by what it reads (typed, not text)."""
    if isinstance(value, Ref):
        return value.read(lookup)
    if isinstance(value, dict):
        return {k: resolve_value(v, lookup) for k, v in value.items()}
    if isinstance(value, list):
        return [resolve_value(v, lookup) for v in value]
    return value


# ---------------------------------------------------------------- nodes


@dataclass(frozen=True, eq=False, kw_only=True)
class Node:
    """A behaviour-tree node as written in the mission.

    Attributes:
        pos: where the node's mapping starts.
        name: the explicit ``name:``, if any.
        field_pos: where the value of each written field starts (type key included).
    """

    kind: ClassVar[str] = "node"
    pos: Pos
    name: str | None = None
    field_pos: Mapping[str, Pos] = field(default_factory=dict)

    def at(self, field_name: str) -> Pos:
        """Position of a field's value, or the node's position if it was not written."""
        return self.field_pos.get(field_name, self.pos)

    @property
    def label(self) -> str:
        """The explicit name, else a short description."""
        return self.name if self.name is not None else self.default_label()

    def default_label(self) -> str:
        return self.kind


@dataclass(frozen=True, eq=False, kw_only=True)
class Composite(Node):
    """A node with an ordered list of children."""

    children: tuple[Node, ...]


@dataclass(frozen=True, eq=False, kw_only=True)
class Sequence(Composite):
    """Children in order until one fails; remembers the running child (memory)."""

    kind: ClassVar[str] = "sequence"


@dataclass(frozen=True, eq=False, kw_only=True)
class ReactiveSequence(Composite):
    """Children in order, re-ticked from the first on every tick (no memory): an earlier
    condition that turns false halts the running child."""

    kind: ClassVar[str] = "reactive_sequence"


@dataclass(frozen=True, eq=False, kw_only=True)
class Selector(Composite):
    """Children in order until one succeeds (fallback); remembers the running child."""

    kind: ClassVar[str] = "selector"


@dataclass(frozen=True, eq=False, kw_only=True)
class ReactiveSelector(Composite):
    """Fallback re-ticked from the first child every tick: a higher-priority child that
    starts succeeding (or running) halts the lower one."""

    kind: ClassVar[str] = "reactive_selector"


class ParallelPolicy(enum.Enum):
    """When a ``parallel`` succeeds. It fails as soon as any child fails."""

    SUCCESS_ON_ALL = "success_on_all"
    """Succeed when every child has succeeded."""
    SUCCESS_ON_ONE = "success_on_one"
    """Succeed when any child succeeds; the others are halted."""
    SUCCESS_ON_SELECTED = "success_on_selected"
    """Succeed when the children named in ``selected`` have succeeded."""


@dataclass(frozen=True, eq=False, kw_only=True)
class Parallel(Composite):
    """Ticks all children every tick."""

    kind: ClassVar[str] = "parallel"
    policy: ParallelPolicy = ParallelPolicy.SUCCESS_ON_ALL
    selected: tuple[str, ...] = ()
    success_count: int | None = None
    failure_count: int | None = None

    @property
    def counted(self) -> bool:
        """Whether it counts successes and failures (``success_count``/``failure_count``)
        instead of following a policy."""
        return self.success_count is not None or self.failure_count is not None


@dataclass(frozen=True, eq=False, kw_only=True)
class ResumeSequence(Composite):
    """A sequence that, after a failure, resumes at the child that failed instead of
    starting over (BehaviorTree.CPP's SequenceWithMemory); it starts over after a
    success."""

    kind: ClassVar[str] = "resume_sequence"


@dataclass(frozen=True, eq=False, kw_only=True)
class PipelineSequence(Composite):
    """Every tick, ticks the children from the first up to the furthest one reached: a
    child that succeeded is ticked (so restarted) again while a later one runs (Nav2's
    PipelineSequence). Fails as soon as one fails; succeeds when all succeed in one
    tick."""

    kind: ClassVar[str] = "pipeline_sequence"


@dataclass(frozen=True, eq=False, kw_only=True)
class IfThenElse(Composite):
    """Two or three children: the first decides, once, which of the others runs (the
    second on success, the third on failure; without a third, failure). The condition
    is not ticked again while the chosen branch runs."""

    kind: ClassVar[str] = "if_then_else"


@dataclass(frozen=True, eq=False, kw_only=True)
class WhileDoElse(Composite):
    """Like ``if_then_else``, but the condition is ticked again on every tick: when its
    outcome changes, the running branch is halted and the other one starts."""

    kind: ClassVar[str] = "while_do_else"


@dataclass(frozen=True, eq=False, kw_only=True)
class Recovery(Composite):
    """Two children: the action and its recovery (Nav2's RecoveryNode). When the action
    fails, the recovery runs; if it succeeds the action is tried again, at most
    ``retries`` times. Fails when the recovery fails or the retries are used up."""

    kind: ClassVar[str] = "recovery"
    retries: int | Ref = 1

    def default_label(self) -> str:
        return f"recovery x{self.retries}"


@dataclass(frozen=True, eq=False, kw_only=True)
class Decorator(Node):
    """A node with one child whose status it transforms."""

    child: Node


@dataclass(frozen=True, eq=False, kw_only=True)
class Retry(Decorator):
    """Run the child up to ``times`` attempts in all (``None``: no limit), until it
    succeeds."""

    kind: ClassVar[str] = "retry"
    times: int | Ref | None

    def default_label(self) -> str:
        return "retry forever" if self.times is None else f"retry x{self.times}"


@dataclass(frozen=True, eq=False, kw_only=True)
class Repeat(Decorator):
    """Run the child until it has succeeded ``times`` times (``None``: forever); fail
    as soon as it fails."""

    kind: ClassVar[str] = "repeat"
    times: int | Ref | None

    def default_label(self) -> str:
        return "repeat forever" if self.times is None else f"repeat x{self.times}"


@dataclass(frozen=True, eq=False, kw_only=True)
class Timeout(Decorator):
    """Fail, halting the child, if it is still running ``seconds`` after it started
    (runtime clock)."""

    kind: ClassVar[str] = "timeout"
    seconds: float | Ref

    def default_label(self) -> str:
        return f"timeout {self.seconds}s"


@dataclass(frozen=True, eq=False, kw_only=True)
class RateController(Decorator):
    """Tick the child at most ``hz`` times a second (Nav2's RateController): after the
    child succeeds, the node is RUNNING until the period has passed, then ticks the
    child again. A running child is ticked on every tick."""

    kind: ClassVar[str] = "rate_controller"
    hz: float | Ref

    def default_label(self) -> str:
        return f"rate {self.hz} Hz"


class RunOnceThen(enum.Enum):
    """What a ``run_once`` node returns after its child has finished once."""

    SAME = "same"
    """The status the child finished with."""
    SUCCESS = "success"
    """Success."""
    FAILURE = "failure"
    """Failure."""


@dataclass(frozen=True, eq=False, kw_only=True)
class RunOnce(Decorator):
    """Tick the child until it finishes, once per run; afterwards return ``then``
    without ticking it."""

    kind: ClassVar[str] = "run_once"
    then: RunOnceThen = RunOnceThen.SAME


@dataclass(frozen=True, eq=False, kw_only=True)
class Invert(Decorator):
    """Success becomes failure and failure success."""

    kind: ClassVar[str] = "invert"


@dataclass(frozen=True, eq=False, kw_only=True)
class ForceSuccess(Decorator):
    """Failure becomes success."""

    kind: ClassVar[str] = "force_success"


@dataclass(frozen=True, eq=False, kw_only=True)
class ForceFailure(Decorator):
    """Success becomes failure."""

    kind: ClassVar[str] = "force_failure"


@dataclass(frozen=True, eq=False, kw_only=True)
class PluginNode(Node):
    """What a control or decorator written in Python (a plugin, see ``_plugins``) is
    given by the mission.

    Attributes:
        plugin: the registered name (``control: RoundRobin``).
        ports: input port values (``with:``): literals or references, in source order.
        outs: output port -> the blackboard key it writes (``out:``).
        port_pos: where each input value starts; out_pos: where each output key starts.
    """

    plugin: str
    ports: Mapping[str, Any] = field(default_factory=dict)
    outs: Mapping[str, str] = field(default_factory=dict)
    port_pos: Mapping[str, Pos] = field(default_factory=dict)
    out_pos: Mapping[str, Pos] = field(default_factory=dict)

    def default_label(self) -> str:
        return self.plugin


@dataclass(frozen=True, eq=False, kw_only=True)
class PluginControl(PluginNode, Composite):
    """``control: Name``: a plugin control node over ``children:``."""

    kind: ClassVar[str] = "control"


@dataclass(frozen=True, eq=False, kw_only=True)
class PluginDecorator(PluginNode, Decorator):
    """``decorator: Name``: a plugin decorator over ``child:``."""

    kind: ClassVar[str] = "decorator"


@dataclass(frozen=True, eq=False, kw_only=True)
class Do(Node):
    """Call an actor (or a tree): ``do: actor``, ``with:`` arguments, ``out:`` key.

    Attributes:
        actor: the name as written, resolved from the root scope.
        args: positional arguments (``with:`` given as a list).
        kwargs: keyword arguments (``with:`` given as a mapping), in source order.
        out: blackboard key that receives the result.
        arg_pos: where each argument's value starts (keys: names, or "0", "1"...).
    """

    kind: ClassVar[str] = "do"
    actor: str
    args: tuple[Any, ...] = ()
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    out: str | None = None
    arg_pos: Mapping[str, Pos] = field(default_factory=dict)
    arg_key_pos: Mapping[str, Pos] = field(default_factory=dict)

    def default_label(self) -> str:
        return self.actor


@dataclass(frozen=True, eq=False, kw_only=True)
class Condition(Do):
    """Ask an actor within the tick: ``condition: actor``, with ``with:`` and ``out:`` as
    for ``do:``.

    The tick waits for the answer, so the node is never RUNNING: it succeeds or fails in
    the tick that reached it. This is what a condition under a reactive parent needs
    (BehaviorTree.CPP's Condition nodes): re-asked on every tick, a ``do:`` leaf would be
    restarted and halt its running siblings each time.
    """

    kind: ClassVar[str] = "condition"


@dataclass(frozen=True, eq=False, kw_only=True)
class SetValues(Node):
    """Write values (literals or references) to the blackboard; always succeeds."""

    kind: ClassVar[str] = "set"
    values: Mapping[str, Any]
    key_pos: Mapping[str, Pos] = field(default_factory=dict)

    def default_label(self) -> str:
        return "set " + ", ".join(self.values)


@dataclass(frozen=True, eq=False, kw_only=True)
class Check(Node):
    """Succeed if the expression holds on the blackboard, fail otherwise (also when it
    cannot be evaluated, e.g. a key that is not set yet).

    Attributes:
        source: the expression text.
        expr: its parsed form.
        key_pos: the position of every key the expression reads.
    """

    kind: ClassVar[str] = "check"
    source: str
    expr: Expr
    key_pos: tuple[tuple[str, Pos], ...] = ()

    def default_label(self) -> str:
        return f"check {self.source}"


@dataclass(frozen=True, eq=False, kw_only=True)
class Wait(Node):
    """Running for ``seconds`` of runtime-clock time, then success."""

    kind: ClassVar[str] = "wait"
    seconds: float | Ref

    def default_label(self) -> str:
        return f"wait {self.seconds}s"


@dataclass(frozen=True, eq=False, kw_only=True)
class UseBehaviour(Node):
    """A registered py_trees Behaviour class or factory: ``behaviour: Name``.

    Attributes:
        behaviour: the registered name.
        kwargs: keyword arguments for the factory (``with:``); references allowed.
        writes: blackboard keys the behaviour writes, so that later references to them
            validate.
    """

    kind: ClassVar[str] = "behaviour"
    behaviour: str
    kwargs: Mapping[str, Any] = field(default_factory=dict)
    writes: tuple[str, ...] = ()
    arg_pos: Mapping[str, Pos] = field(default_factory=dict)

    def default_label(self) -> str:
        return self.behaviour


Leaf = Union[Do, SetValues, Check, Wait, UseBehaviour]


def children_of(node: Node) -> tuple[Node, ...]:
    """The direct children of a node."""
    if isinstance(node, Composite):
        return node.children
    if isinstance(node, Decorator):
        return (node.child,)
    return ()


def walk(node: Node) -> Iterator[Node]:
    """The node and all its descendants, depth first, in source order."""
    yield node
    for child in children_of(node):
        yield from walk(child)


# ---------------------------------------------------------------- mission


@dataclass(frozen=True, eq=False)
class InputSpec:
    """One tree input: a parameter of the tree as an actor, seeded on the blackboard."""

    name: str
    type: ValueType
    default: Any
    doc: str | None
    pos: Pos

    @property
    def required(self) -> bool:
        return self.default is REQUIRED


@dataclass(frozen=True, eq=False)
class OutputSpec:
    """One tree output: a blackboard key returned in the tree's result mapping."""

    name: str
    type: ValueType
    doc: str | None
    pos: Pos


@dataclass(frozen=True, eq=False)
class Mission:
    """A parsed mission file.

    Attributes:
        name: the tree's actor name.
        doc: what it does (the actor's docstring).
        inputs: parameters, in declaration order.
        outputs: blackboard keys returned as ``{name: value}``.
        root: the root node.
        file: where it was read from.
        source: the file text (hashed into trace headers).
        pos: where the mission mapping starts.
    """

    name: str
    doc: str | None
    inputs: tuple[InputSpec, ...]
    outputs: tuple[OutputSpec, ...]
    root: Node
    file: str
    source: str
    pos: Pos

    @property
    def source_hash(self) -> str:
        """sha256 of the file text."""
        return hashlib.sha256(self.source.encode("utf-8")).hexdigest()

    def input(self, name: str) -> InputSpec | None:
        for spec in self.inputs:
            if spec.name == name:
                return spec
        return None

    def signature(self) -> inspect.Signature:
        """The tree's signature as an actor: inputs as parameters, in order.

        An input without a default that follows one with a default becomes keyword-only,
        so the signature stays valid Python.
        """
        params = []
        seen_default = False
        for spec in self.inputs:
            kind = (
                inspect.Parameter.KEYWORD_ONLY
                if spec.required and seen_default
                else inspect.Parameter.POSITIONAL_OR_KEYWORD
            )
            seen_default = seen_default or not spec.required
            params.append(
                inspect.Parameter(
                    spec.name,
                    kind,
                    default=inspect.Parameter.empty if spec.required else spec.default,
                    annotation=spec.type.python_type,
                )
            )
        params.sort(key=lambda p: p.kind)  # keyword-only after positional, stable
        return inspect.Signature(params, return_annotation=dict)

    def bind_inputs(self, *args: Any, **kwargs: Any) -> dict[str, Any]:
        """Inputs for one run: arguments bound to the signature, defaults applied,
        types checked.

        Raises:
            InputError: unknown or missing inputs, or a value of the wrong type.
        """
        sig = self.signature()
        try:
            bound = sig.bind(*args, **kwargs)
        except TypeError as exc:
            raise InputError(f"tree {self.name!r}: {exc}; expected {self.name}{sig}") from None
        bound.apply_defaults()
        values = dict(bound.arguments)
        for spec in self.inputs:
            value = values[spec.name]
            if not spec.type.accepts(value):
                raise InputError(
                    f"tree {self.name!r}: input {spec.name!r} is {value!r} "
                    f"({type(value).__name__}), expected {spec.type.value}"
                )
        return values
