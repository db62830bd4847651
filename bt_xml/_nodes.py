"""The node model: a ``<TreeNodesModel>`` (the palette a project ships for Groot) that
declares nodes implemented elsewhere, their kind and their typed ports.

It serves twice: the importer reads port directions and types from it (which attribute
is an argument, which a result, how to convert a literal), and ``actorbt check --nodes``
turns each declared leaf into an actor signature, so that missions calling nodes that
are not implemented here (a Nav2 tree without Nav2) still validate.
"""

from __future__ import annotations

import enum
import inspect
import json
import math
import re
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from bt_engine.errors import ActorbtError, UnknownActorError
from bt_engine.trees import UNSET, InputPort, OutputPort, PluginSpec
from ._errors import BtXmlError, Pos, UnknownXmlNodeError
from ._source import XElement, read_xml

__all__ = [
    "JSON_PREFIX",
    "ModelResolver",
    "NodeKind",
    "NodeModel",
    "NodeSpec",
    "PortDirection",
    "PortSpec",
    "convert_literal",
    "decode_json",
    "guess_literal",
    "plugin_ports",
    "python_type",
    "read_node_model",
]

#: port text that holds a JSON value (BehaviorTree.CPP v4's prefix; see ``_values``)
JSON_PREFIX = "json:"


class NodeKind(enum.Enum):
    """What a declared node is, as its model element says."""

    ACTION = "Action"
    """A leaf that does something: an actor call."""
    CONDITION = "Condition"
    """A leaf that tests something: an actor call that returns True or False."""
    CONTROL = "Control"
    """A node with several children."""
    DECORATOR = "Decorator"
    """A node with one child."""
    SUBTREE = "SubTree"
    """A tree, with its ports."""


class PortDirection(enum.Enum):
    """Which way a port passes data."""

    INPUT = "input_port"
    """An argument of the actor."""
    OUTPUT = "output_port"
    """Part of the actor's result, written to the blackboard."""
    INOUT = "inout_port"
    """Both."""


@dataclass(frozen=True)
class PortSpec:
    """One port of a declared node.

    Attributes:
        name: the attribute name.
        direction: input, output or both.
        type: the C++ (or Python) type as written, "" if none.
        default: the default as written, or None.
        description: the element's text.
        pos: where the port is declared.
    """

    name: str
    direction: PortDirection
    type: str
    default: str | None
    description: str
    pos: Pos

    @property
    def reads(self) -> bool:
        return self.direction is not PortDirection.OUTPUT

    @property
    def writes(self) -> bool:
        return self.direction is not PortDirection.INPUT


@dataclass(frozen=True)
class NodeSpec:
    """One declared node: its ID, kind, ports and description."""

    id: str
    kind: NodeKind
    ports: tuple[PortSpec, ...]
    description: str
    pos: Pos

    def port(self, name: str) -> PortSpec | None:
        return next((p for p in self.ports if p.name == name), None)

    @property
    def outputs(self) -> tuple[PortSpec, ...]:
        return tuple(p for p in self.ports if p.writes)

    def signature(self) -> inspect.Signature:
        """The actor signature its input ports give: keyword parameters, typed where the
        type is a plain one, with the declared defaults (converted). A port without a
        default is optional, as in BehaviorTree.CPP: left out, it is unset (its default
        is :data:`~bt_engine.trees.UNSET`), and the node fails only if it reads it."""
        params = []
        for port in self.ports:
            if not port.reads:
                continue
            default: Any = UNSET
            if port.default is not None and not _is_reference(port.default):
                default = self._default(port)
            elif port.default is not None or port.writes:
                default = None
            params.append(
                inspect.Parameter(
                    port.name, inspect.Parameter.KEYWORD_ONLY, default=default, annotation=python_type(port.type)
                )
            )
        return inspect.Signature(params, return_annotation=inspect.Signature.empty)

    def _default(self, port: PortSpec) -> Any:
        """A port's declared default, converted by its type.

        Raises:
            BtXmlError: at the port, the default is not a value of its type.
        """
        assert port.default is not None
        try:
            return convert_literal(port.default, port.type)
        except ValueError as exc:
            raise BtXmlError(port.pos, f"the default of port '{port.name}' of node '{self.id}': {exc}") from None

    def plugin_spec(self) -> PluginSpec:
        """A Control or Decorator as the spec of a plugin that is still to be written
        (``cls`` None): missions that use it validate, and ``check`` says it is missing."""
        ports: dict[str, InputPort | OutputPort] = {}
        for port in self.ports:
            annotation = python_type(port.type)
            ptype = Any if annotation is inspect.Parameter.empty else annotation
            if port.reads:
                default: Any = UNSET
                if port.default is not None:
                    default = port.default if _is_reference(port.default) else self._default(port)
                ports[port.name] = InputPort(ptype, default, port.description)
            else:
                ports[port.name] = OutputPort(ptype, port.description)
        kind = "control" if self.kind is NodeKind.CONTROL else "decorator"
        return PluginSpec(self.id, kind, ports, self.description, (1, None) if kind == "control" else (1, 1))


_INT_TYPES = re.compile(r"(unsigned\s+)?(int|long|short|size_t|u?int\d+_t|std::u?int\d+_t)\Z")
_FLOAT_TYPES = ("double", "float")
_STR_TYPES = ("std::string", "string", "str", "BT::StringView", "std::string_view")


def python_type(type_name: str) -> Any:
    """The Python annotation for a declared port type; ``inspect.Parameter.empty`` when
    it is not a plain number, boolean or string (the validator then does not check it)."""
    t = type_name.strip()
    if _INT_TYPES.match(t):
        return int
    if t in _FLOAT_TYPES:
        return float
    if t == "bool":
        return bool
    if t in _STR_TYPES:
        return str
    return inspect.Parameter.empty


_INT = re.compile(r"[+-]?[0-9]+\Z")
#: a number as std::stod reads one (also inf, infinity and nan, in any case)
_FLOAT = re.compile(r"[+-]?(([0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)([eE][+-]?[0-9]+)?|inf|infinity|nan)\Z", re.I)
#: a C++ numeric limit as node models write defaults: ``std::numeric_limits<double>::infinity()``
_LIMIT = re.compile(
    r"(?P<sign>[+-]?)\s*(std::)?numeric_limits\s*<\s*(?P<type>[\w:\s]+?)\s*>\s*::\s*"
    r"(?P<which>infinity|max|lowest|min|epsilon)\s*\(\s*\)\Z"
)
_FLOAT_LIMITS = {
    "infinity": math.inf,
    "max": sys.float_info.max,
    "lowest": -sys.float_info.max,
    "min": sys.float_info.min,
    "epsilon": sys.float_info.epsilon,
}
#: bits of the integer types a limit may name (signed unless ``unsigned``/``uint``)
_INT_BITS = {"short": 16, "int": 32, "long": 64, "size_t": 64}


def numeric_limit(text: str) -> float | int | None:
    """The value of a ``numeric_limits<T>::which()`` default, or None for other text.
    Floating types are taken as double; BehaviorTree.CPP reads these defaults as C++."""
    found = _LIMIT.match(text.strip())
    if found is None:
        return None
    ctype, which = found["type"].replace("std::", "").strip(), found["which"]
    value: float | int
    if ctype in _FLOAT_TYPES:
        value = _FLOAT_LIMITS[which]
    else:
        bits_match = re.search(r"(\d+)_t\Z", ctype)
        bits = int(bits_match.group(1)) if bits_match else _INT_BITS.get(ctype.split()[-1], 32)
        unsigned = ctype.startswith(("unsigned", "uint", "size_t"))
        top = 2**bits - 1 if unsigned else 2 ** (bits - 1) - 1
        bottom = 0 if unsigned else -top - 1
        limits = {"max": top, "lowest": bottom, "min": bottom, "infinity": 0, "epsilon": 0}
        value = limits[which]
    return -value if found["sign"] == "-" else value


def _is_reference(text: str) -> bool:
    return text.startswith("{") and text.endswith("}")


def guess_literal(text: str) -> Any:
    """An attribute without a declared type: ``true``/``false`` as booleans, numbers as
    numbers, anything else as the string."""
    if text in ("true", "false"):
        return text == "true"
    if _INT.match(text):
        return int(text)
    if _FLOAT.match(text) and any(c.isdigit() for c in text):
        return float(text)
    return text


def decode_json(text: str) -> Any:
    """The value of ``json:`` text.

    Raises:
        ValueError: the text after ``json:`` is not JSON.
    """
    try:
        return json.loads(text.strip()[len(JSON_PREFIX) :])
    except json.JSONDecodeError as exc:
        raise ValueError(f"the text after 'json:' is not JSON ({exc.msg} at character {exc.pos + 1})") from None


def convert_literal(text: str, type_name: str) -> Any:
    """An attribute's text converted by its port's declared type (unknown types: guessed
    for numbers and booleans only when the type says nothing; strings stay strings);
    ``json:`` text is decoded whatever the type.

    Raises:
        ValueError: the text is not a value of that type.
    """
    if text.strip().startswith(JSON_PREFIX):
        return decode_json(text)
    annotation = python_type(type_name)
    limit = numeric_limit(text) if annotation in (int, float) else None
    if limit is not None:
        return annotation(limit)
    if annotation is int:
        if not _INT.match(text.strip()):
            raise ValueError(f"{text!r} is not an integer")
        return int(text)
    if annotation is float:
        if not _FLOAT.match(text.strip()):
            raise ValueError(f"{text!r} is not a number")
        return float(text)
    if annotation is bool:
        lowered = text.strip().lower()
        if lowered not in ("true", "false", "1", "0"):
            raise ValueError(f"{text!r} is not a boolean (true or false)")
        return lowered in ("true", "1")
    if annotation is str:
        return text
    return guess_literal(text) if not type_name.strip() else text


class NodeModel:
    """Nodes declared by ``<TreeNodesModel>`` elements, by ID."""

    def __init__(self, nodes: Iterable[NodeSpec] = (), files: Iterable[str] = ()) -> None:
        self.nodes: dict[str, NodeSpec] = {}
        self.files = list(files)
        for node in nodes:
            self.nodes[node.id] = node

    def __contains__(self, node_id: object) -> bool:
        return node_id in self.nodes

    def __getitem__(self, node_id: str) -> NodeSpec:
        return self.nodes[node_id]

    def get(self, node_id: str) -> NodeSpec | None:
        return self.nodes.get(node_id)

    def __len__(self) -> int:
        return len(self.nodes)

    def add_element(self, model: XElement) -> None:
        """Add the nodes of one ``<TreeNodesModel>`` element.

        Raises:
            BtXmlError: an unknown element, a node without an ID, a port without a name.
        """
        kinds = {k.value: k for k in NodeKind}
        for element in model.children:
            if element.tag not in kinds:
                from bt_engine.trees import suggest

                raise UnknownXmlNodeError(
                    element.pos,
                    f"unknown node kind <{element.tag}> in TreeNodesModel{suggest(element.tag, kinds)}, "
                    f"expected one of: {', '.join(kinds)}",
                )
            node_id = element.attrs.get("ID")
            if not node_id:
                raise BtXmlError(element.pos, f'<{element.tag}> has no ID, expected e.g. <{element.tag} ID="Name">')
            ports = []
            description = ""
            for child in element.children:
                if child.tag == "description":
                    description = child.text
                    continue
                try:
                    direction = PortDirection(child.tag)
                except ValueError:
                    continue  # Groot's metadata elements
                name = child.attrs.get("name")
                if not name:
                    raise BtXmlError(child.pos, f'<{child.tag}> has no name, expected e.g. <{child.tag} name="goal">')
                ports.append(
                    PortSpec(
                        name, direction, child.attrs.get("type", ""), child.attrs.get("default"), child.text, child.pos
                    )
                )
            description = description or element.attrs.get("description", "") or element.text
            self.nodes[node_id] = NodeSpec(node_id, kinds[element.tag], tuple(ports), description, element.pos)

    def plugins(self, registered: dict[str, PluginSpec]) -> dict[str, PluginSpec]:
        """The plugins ``registered``, plus the model's Controls and Decorators that none
        of them implements (as unwritten plugins, see :meth:`NodeSpec.plugin_spec`)."""
        found = dict(registered)
        for node_id, spec in self.nodes.items():
            if spec.kind in (NodeKind.CONTROL, NodeKind.DECORATOR) and node_id not in found:
                found[node_id] = spec.plugin_spec()
        return found

    def resolver(self, fallback: Callable[[str], Any] | None = None) -> "ModelResolver":
        """An actor resolver (for ``check``) that knows the declared leaves, then ``fallback``."""
        return ModelResolver(self, fallback)


@dataclass(frozen=True)
class _ModelActor:
    path: str
    signature: inspect.Signature
    is_tree: bool = False
    doc: str | None = None
    kind: str = "sync"


class ModelResolver:
    """``name -> actor info``: the model's Action and Condition nodes first, then the
    fallback resolver; unknown names raise UnknownActorError with close matches."""

    def __init__(self, model: NodeModel, fallback: Callable[[str], Any] | None = None) -> None:
        self.model = model
        self.fallback = fallback

    def __call__(self, name: str) -> Any:
        spec = self.model.get(name)
        if spec is not None and spec.kind in (NodeKind.ACTION, NodeKind.CONDITION):
            return _ModelActor(name, spec.signature(), doc=spec.description or None)
        leaves = [n for n, s in self.model.nodes.items() if s.kind in (NodeKind.ACTION, NodeKind.CONDITION)]
        if self.fallback is not None:
            try:
                return self.fallback(name)
            except (LookupError, ActorbtError) as exc:
                suggestions = getattr(exc, "suggestions", None)
                if suggestions is None:
                    raise
                raise UnknownActorError(name, [*leaves, *suggestions]) from None
        raise UnknownActorError(name, leaves)


_CPP_TYPES = {float: "double", int: "int", bool: "bool", str: "std::string"}


def plugin_ports(plugin: PluginSpec | None, pos: Pos) -> dict[str, PortSpec]:
    """A registered plugin's ports as a node model declares them (for the importer)."""
    ports: dict[str, PortSpec] = {}
    for name, port in (plugin.ports if plugin is not None else {}).items():
        cpp = _CPP_TYPES.get(port.type, "")
        if isinstance(port, InputPort):
            default = None
            if port.default is not UNSET:
                default = port.default if isinstance(port.default, str) else json.dumps(port.default)
            ports[name] = PortSpec(name, PortDirection.INPUT, cpp, default, port.doc, pos)
        else:
            ports[name] = PortSpec(name, PortDirection.OUTPUT, cpp, None, port.doc, pos)
    return ports


def read_node_model(paths: Iterable[str | Path]) -> NodeModel:
    """The nodes declared in these files: each may be a ``<root>`` holding
    ``<TreeNodesModel>`` elements (and trees, ignored here) or a bare ``<TreeNodesModel>``.

    Raises:
        BtXmlError: a file that does not parse or holds no node model.
    """
    model = NodeModel()
    for path in paths:
        top = read_xml(path)
        models = [top] if top.tag == "TreeNodesModel" else [c for c in top.children if c.tag == "TreeNodesModel"]
        if not models:
            raise BtXmlError(top.pos, f"{path} holds no <TreeNodesModel>, expected a node model (Groot palette) file")
        for element in models:
            model.add_element(element)
        model.files.append(str(path))
    return model
