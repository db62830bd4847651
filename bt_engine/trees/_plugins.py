"""Control and decorator nodes written in Python: how a plugin declares itself.

A plugin is a class (see :mod:`._plugin_nodes` for what it may do when it runs) marked
with :func:`control_node` or :func:`decorator_node`. The mark records a
:class:`PluginSpec`: its name, its kind, its ports and how many children it takes, and
registers it, so that a mission names it (``control: RoundRobin``) as it names an actor.
Registration happens when the module that defines the class is imported: list the module
under ``imports:`` in ``actorbt.yaml`` (actorbt's own Nav2 nodes are always there).

Ports are declared as BehaviorTree.CPP declares them (``providedPorts``): an input port
may have a default; one without a default that the mission leaves out is *unset*, and
reading it fails the node at run time, with a message that names the port.
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, TypeVar

from ..errors import ActorbtError

__all__ = [
    "UNSET",
    "InputPort",
    "OutputPort",
    "PluginSpec",
    "PortUnsetError",
    "control_node",
    "decorator_node",
    "node_plugins",
    "plugin_spec",
    "register_node",
]


class _Unset:
    """Marker: an input port without a default (BehaviorTree.CPP: an optional port)."""

    def __repr__(self) -> str:
        return "unset"


UNSET: Any = _Unset()


class PortUnsetError(ActorbtError, KeyError):
    """A node read an input port that the mission left out and that has no default."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


@dataclass(frozen=True)
class InputPort:
    """An input of a plugin node: a literal or a ``"{key}"`` reference in the mission.

    Attributes:
        type: the Python type a value must have (``float``, ``str``, ``dict``...; ``Any``:
            unchecked); literals and typed references are checked at load time.
        default: the value when the mission leaves the port out; a ``"{key}"`` default
            reads that blackboard key (unset when the key is). :data:`UNSET`: none.
        doc: what the port is, with its unit in square brackets.
        actor: the value names an actor the node calls; a name written in the mission is
            resolved at load time, like a ``do:`` target.
    """

    type: Any = Any
    default: Any = UNSET
    doc: str = ""
    actor: bool = False


@dataclass(frozen=True)
class OutputPort:
    """An output of a plugin node: the mission maps it to a blackboard key (``out:``)."""

    type: Any = Any
    doc: str = ""


Port = InputPort | OutputPort


@dataclass(frozen=True)
class PluginSpec:
    """What a mission needs to know about a plugin node.

    Attributes:
        name: the name missions use (``control: RoundRobin``).
        kind: ``control`` or ``decorator``.
        ports: input and output ports by name, in declaration order.
        doc: the class docstring.
        child_count: (fewest, most) children; ``None``: no upper bound. A decorator
            has exactly one.
        cls: the class, or ``None`` for a node a node model declares that nobody has
            written yet (``actorbt check --nodes``): it validates but cannot run.
    """

    name: str
    kind: str
    ports: Mapping[str, Port] = field(default_factory=dict)
    doc: str = ""
    child_count: tuple[int, int | None] = (1, None)
    cls: type | None = None

    @property
    def inputs(self) -> dict[str, InputPort]:
        return {n: p for n, p in self.ports.items() if isinstance(p, InputPort)}

    @property
    def outputs(self) -> dict[str, OutputPort]:
        return {n: p for n, p in self.ports.items() if isinstance(p, OutputPort)}

    @property
    def module(self) -> str | None:
        """The module that defines the class (traces record it, replay imports it)."""
        return self.cls.__module__ if self.cls is not None else None

    @property
    def implemented(self) -> bool:
        return self.cls is not None


#: every plugin defined so far, by name (filled when their modules are imported)
_REGISTRY: dict[str, PluginSpec] = {}

#: the attribute the marks set on a plugin class
SPEC_ATTR = "_plugin_spec"

C = TypeVar("C", bound=type)


def plugin_spec(cls: type) -> PluginSpec | None:
    """The spec a class was marked with, if any."""
    spec = cls.__dict__.get(SPEC_ATTR)
    return spec if isinstance(spec, PluginSpec) else None


def register_node(cls: type, *, replace: bool = True) -> PluginSpec:
    """Register a marked class (the marks do this); returns its spec.

    Raises:
        TypeError: the class is not marked, or (``replace=False``) its name is taken by
            another class.
    """
    spec = plugin_spec(cls)
    if spec is None:
        raise TypeError(f"{cls.__qualname__} is not marked with @control_node or @decorator_node")
    other = _REGISTRY.get(spec.name)
    if other is not None and other.cls is not cls and not replace:
        raise TypeError(f"node {spec.name!r} is already {other.cls.__qualname__ if other.cls else 'declared'}")
    _REGISTRY[spec.name] = spec
    return spec


def node_plugins() -> dict[str, PluginSpec]:
    """Every registered plugin, by name (a copy)."""
    return dict(_REGISTRY)


def _mark(kind: str, base: str, name: str | None, child_count: tuple[int, int | None]) -> Callable[[C], C]:
    def mark(cls: C) -> C:
        if not any(b.__name__ == base for b in cls.__mro__):
            raise TypeError(f"@{kind}_node: {cls.__qualname__} must subclass {base}")
        ports = dict(getattr(cls, "ports", {}) or {})
        for port_name, port in ports.items():
            if not isinstance(port, (InputPort, OutputPort)):
                raise TypeError(
                    f"{cls.__qualname__}.ports[{port_name!r}] is {port!r}, expected InputPort or OutputPort"
                )
        lo, hi = child_count
        if lo < 1 or hi is not None and hi < lo:
            raise TypeError(f"@{kind}_node: child_count {child_count!r} is not a range of at least one child")
        spec = PluginSpec(name or cls.__name__, kind, ports, inspect.cleandoc(cls.__doc__ or ""), child_count, cls)
        setattr(cls, SPEC_ATTR, spec)
        register_node(cls)
        return cls

    return mark


def control_node(name: str | None = None, *, children: tuple[int, int | None] = (1, None)) -> Callable[[C], C]:
    """Mark and register a :class:`~._plugin_nodes.ControlNode` subclass as the control
    ``name`` (default: the class name) taking ``children`` = (fewest, most) children."""
    return _mark("control", "ControlNode", name, children)


def decorator_node(name: str | None = None) -> Callable[[C], C]:
    """Mark and register a :class:`~._plugin_nodes.DecoratorNode` subclass as the
    decorator ``name`` (default: the class name)."""
    return _mark("decorator", "DecoratorNode", name, (1, 1))
