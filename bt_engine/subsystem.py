"""SubSystem and SubNet: where actors live, and how names are found.

A SubSystem is a class whose constructor declares persistent values and edges to the
outside world (publishers, subscribers, child subsystems); its ``@actor`` methods are its
actors. A SubNet holds actors only, like an ``#include``.

Name lookup from a scope: the scope's own actors, then a unique match among its
descendants, then the same from its parent, up to the root. A name defined in two
subsystems below the scope where it is looked up is ambiguous. A dotted name
(``robot.navigation.goto``) is absolute.
"""

from __future__ import annotations

import inspect
from typing import Any, Callable, Self, TypeVar

from .actor import SPEC_ATTR, ActorRef, ActorSpec, Safety
from .api import CallApi
from .bus.messages import RosAction
from .bus.qos import qos_depth
from .bus.transport import Publisher, silence
from .errors import ActorbtError, AmbiguousActorError, UnknownActorError
from .modes import Kind
from .transaction import TransactionTable

#: a SubSystem class, so that add_subsystem returns what it was given
_S = TypeVar("_S", bound="SubSystem")

_MISSING = object()

#: How long a call of a subscriber actor waits for a message [s, runtime clock] before it
#: fails with ActorTimeout naming the topic (``register_subscriber(wait=)``). A 1 Hz topic
#: sends one within 1 s; over ROS the publisher must first be discovered (about 2.3 s
#: between processes on one machine, a latched message comes right after), so 10 s is
#: several times the slowest healthy case and still an answer a person at the terminal
#: waits for. It matches how long an action or service actor waits for its server.
SUBSCRIBER_WAIT = 10.0


class SubSystem(CallApi):
    """A named scope of actors with persistent values.

    Subclass it, declare values and edges in ``__init__`` (after ``super().__init__()``),
    and write actors as ``@actor`` methods. The runtime creates instances; do not call
    the class yourself. A ros_actor-style constructor ``__init__(self, name, parent)``
    also works: it receives the subsystem's name and parent.
    """

    def __init__(self, name: str | None = None, parent: "SubSystem | None" = None) -> None:
        # The runtime binds _rt/_name/_parent before __init__ runs (see _create), so a
        # subclass constructor can already call set_value and register_*; the
        # arguments exist only for ros_actor-style subclasses that pass them on.
        pass

    #: the Runtime that owns this subsystem (typed loosely: the runtime module builds on
    #: this one, not the other way round)
    _rt: Any

    @classmethod
    def _create(cls, rt: Any, name: str, parent: "SubSystem | None", *args: Any, **kwargs: Any) -> Self:
        obj = cls.__new__(cls)
        obj._bind(rt, name, parent)
        if not args and not kwargs and _wants_args(cls.__init__, 2):
            args = (name, parent)  # ros_actor's SubSystem(name, parent)
        cls.__init__(obj, *args, **kwargs)
        obj._collect_actors(obj)
        return obj

    def _bind(self, rt: Any, name: str, parent: "SubSystem | None") -> None:
        self._rt = rt
        self._name = name
        self._parent = parent
        self._children: dict[str, SubSystem] = {}
        self._actors: dict[str, ActorRef] = {}
        self._values: dict[str, Any] = {}
        self._cache: dict[str, ActorRef] = {}
        self._cache_version = -1
        self._edges: list[Publisher] = []

    # -- identity ----------------------------------------------------------------------
    @property
    def runtime(self) -> Any:
        """The Runtime this subsystem belongs to."""
        return self._rt

    def _txns(self) -> TransactionTable:
        return self._rt.txns

    @property
    def path(self) -> str:
        """Dotted path from the root ('' for the root)."""
        if self._parent is None:
            return ""
        pp = self._parent.path
        return f"{pp}.{self._name}" if pp else self._name

    def _actor_path(self, name: str) -> str:
        p = self.path
        return f"{p}.{name}" if p else name

    def _call_scope(self) -> "SubSystem":
        return self

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.path or '(root)'}>"

    # -- structure ---------------------------------------------------------------------
    def add_subsystem(self, name: str, cls: type[_S], *args: Any, **kwargs: Any) -> _S:
        """Create a child subsystem ``name`` of class ``cls`` and return it."""
        if not (isinstance(cls, type) and issubclass(cls, SubSystem)):
            raise ActorbtError(f"add_subsystem({name!r}, ...) needs a SubSystem class, got {cls!r}")
        if not name or "." in name:
            raise ActorbtError(f"subsystem name {name!r} must be non-empty and contain no '.'")
        if name in self._children:
            raise ActorbtError(f"{self!r} already has a subsystem named {name!r}")
        child = cls._create(self._rt, name, self, *args, **kwargs)
        self._children[name] = child
        self._rt._topology_changed()
        return child

    register_subsystem = add_subsystem  # ros_actor's name

    def remove_subsystem(self, name: str) -> "SubSystem":
        """Detach child subsystem ``name`` and return it (closing it is the caller's:
        its ``close()``, if it has one). Calls under way keep running."""
        try:
            child = self._children.pop(name)
        except KeyError:
            raise ActorbtError(f"{self!r} has no subsystem named {name!r}") from None
        self._rt._topology_changed()
        return child

    def add_network(self, net_cls: type["SubNet"]) -> "SubNet":
        """Include the actors of a SubNet class in this subsystem."""
        if not (isinstance(net_cls, type) and issubclass(net_cls, SubNet)):
            raise ActorbtError(f"add_network needs a SubNet class, got {net_cls!r}")
        net = net_cls.__new__(net_cls)
        net._subsystem = self
        net_cls.__init__(net, *((self,) if _wants_args(net_cls.__init__, 1) else ()))  # ros_actor: SubNet(subsystem)
        self._collect_actors(net)
        return net

    def add_actor(
        self,
        name: str,
        fn: Callable,
        kind: "str | Kind" = Kind.SYNC,
        *,
        doc: str | None = None,
        signature: inspect.Signature | None = None,
        is_tree: bool = False,
        buffer: int | None = None,
        replace: bool = False,
        hub_only: bool = False,
        safety: Safety | None = None,
        wait: float | None = None,
        wait_detail: Callable[[float], str] | None = None,
    ) -> ActorRef:
        """Register a plain callable as an actor of this subsystem (trees, bus edges);
        ``safety``: whether it moves the robot, is read-only, its limits (see @actor);
        ``wait`` / ``wait_detail`` (an emit-style stream): how long a caller waits for a
        value and what the ActorTimeout then says (see :class:`~bt_engine.actor.ActorRef`)."""
        k = Kind.parse(kind)
        if inspect.isgeneratorfunction(fn):
            k = Kind.STREAM
        if name in self._actors and not replace:
            raise ActorbtError(f"{self._actor_path(name)} is already defined")
        ref = ActorRef.build(
            self._actor_path(name),
            name,
            fn,
            k,
            owner=self,
            doc=doc,
            signature=signature,
            is_tree=is_tree,
            hub_only=hub_only,
            safety=safety,
            wait=wait,
            wait_detail=wait_detail,
            **({"buffer": buffer} if buffer else {}),
        )
        self._actors[name] = ref
        self._rt._topology_changed()
        return ref

    def remove_actor(self, name: str) -> bool:
        """Unregister actor ``name`` of this subsystem (a tree whose file was removed);
        False when there is none. Calls under way keep running."""
        if self._actors.pop(name, None) is None:
            return False
        self._rt._topology_changed()
        return True

    def _collect_actors(self, holder: "SubSystem | SubNet") -> None:
        seen: set[str] = set()
        for klass in type(holder).__mro__:
            for attr, val in vars(klass).items():
                spec: ActorSpec | None = getattr(val, SPEC_ATTR, None)
                if spec is None or attr in seen:
                    continue
                seen.add(attr)
                bound = getattr(holder, attr)
                self.add_actor(
                    spec.name or attr, bound, spec.kind, buffer=spec.buffer, hub_only=spec.hub_only, safety=spec.safety
                )

    @property
    def children(self) -> dict[str, "SubSystem"]:
        return dict(self._children)

    def actors(self) -> dict[str, ActorRef]:
        """This subsystem's own actors by name."""
        return dict(self._actors)

    def walk(self):
        """Yield this subsystem and every descendant, depth first."""
        yield self
        for c in self._children.values():
            yield from c.walk()

    def all_actors(self) -> list[ActorRef]:
        """Every actor at or below this subsystem."""
        return [ref for s in self.walk() for ref in s._actors.values()]

    # -- lookup ------------------------------------------------------------------------
    def resolve(self, name: str) -> ActorRef:
        """The actor ``name`` as seen from this scope (see the module docstring)."""
        if self._cache_version == self._rt._topology_version:
            ref = self._cache.get(name)
            if ref is not None:
                return ref
        else:
            self._cache.clear()
            self._cache_version = self._rt._topology_version
        ref = self._lookup(name)
        self._cache[name] = ref
        return ref

    def _lookup(self, name: str) -> ActorRef:
        if not isinstance(name, str) or not name:
            raise UnknownActorError(str(name), [], self.path)
        if "." in name:
            return self._lookup_absolute(name)
        scope: SubSystem | None = self
        while scope is not None:
            ref = scope._actors.get(name)
            if ref is not None:
                return ref
            found = [r for s in scope._children.values() for r in s.all_actors() if r.name == name]
            if len(found) == 1:
                return found[0]
            if len(found) > 1:
                raise AmbiguousActorError(name, [r.path for r in found])
            scope = scope._parent
        raise UnknownActorError(name, self._rt.root._known_names(), self.path)

    def _lookup_absolute(self, dotted: str) -> ActorRef:
        *subs, leaf = dotted.split(".")
        node = self._rt.root
        for s in subs:
            nxt = node._children.get(s)
            if nxt is None:
                raise UnknownActorError(dotted, self._rt.root._known_names(), self.path)
            node = nxt
        ref = node._actors.get(leaf)
        if ref is None:
            raise UnknownActorError(dotted, self._rt.root._known_names(), self.path)
        return ref

    def _known_names(self) -> list[str]:
        refs = self.all_actors()
        return [r.path for r in refs] + [r.name for r in refs]

    # -- persistent values -----------------------------------------------------------
    def set_value(self, key: str, value: Any) -> None:
        """Store a persistent value in this subsystem."""
        self._values[key] = value

    def get_value(self, key: str, default: Any = _MISSING) -> Any:
        """A persistent value from this subsystem or the nearest parent that has it."""
        scope: SubSystem | None = self
        while scope is not None:
            if key in scope._values:
                return scope._values[key]
            scope = scope._parent
        if default is not _MISSING:
            return default
        raise KeyError(f"no value {key!r} in {self!r} or its parents")

    # -- edges to the outside world (bus) --------------------------------------------
    def register_publisher(
        self, name: str, msg_type: type, topic: str, qos: Any = 10, *, moves: bool = False
    ) -> ActorRef:
        """Make actor ``name(msg)`` that publishes ``msg`` on ``topic``. ``qos``: a depth,
        a name ("sensor", "latched", "reliable") or an rclpy QoSProfile. ``moves``: what
        it publishes commands motion (``/cmd_vel``), see :class:`~bt_engine.actor.Safety`."""
        pub = self._rt.bus.publisher(_topic(topic), msg_type, qos)
        self._edges.append(pub)

        def publish(msg: Any) -> None:
            if not isinstance(msg, msg_type):
                raise TypeError(f"{name} publishes {msg_type.__name__}, got {type(msg).__name__}")
            pub.publish(msg)

        type_name = f"{msg_type.__module__}.{msg_type.__name__}"
        publish.__doc__ = (
            f"Publish a {type_name} on {_topic(topic)}.\n\nArgs:\n    msg: the {type_name} message to publish\n"
        )
        return self.add_actor(
            name,
            publish,
            Kind.SYNC,
            signature=inspect.Signature(
                [inspect.Parameter("msg", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation=msg_type)]
            ),
            safety=Safety(moves=moves),
        )

    def register_subscriber(
        self, name: str, msg_type: type, topic: str, qos: Any = 10, *, wait: float | None = SUBSCRIBER_WAIT
    ) -> ActorRef:
        """Make stream actor ``name`` that emits each message arriving on ``topic``;
        its buffer keeps as many of the latest messages as the ``qos`` depth. On a
        transport that delivers on the hub (the local bus) it is ``hub_only``.

        ``wait`` [s, runtime clock]: a caller waiting longer for a message (a sync call,
        the next item of an iterator, the gap between values of the multi mode) fails
        with ActorTimeout naming the topic, its type and whether anything publishes it;
        None waits forever. The stream itself may go on for as long as messages come,
        and a caller's own deadline (``timeout=``, the timed modes) replaces ``wait``."""
        bus = self._rt.bus
        t = _topic(topic)

        def subscribe(emit: Callable[[Any], None]) -> Callable[[], None]:
            return bus.subscribe(t, msg_type, emit, qos).close

        subscribe.__doc__ = f"Messages ({msg_type.__module__}.{msg_type.__name__}) arriving on {t}." + (
            f"\n\nWaiting more than {wait:g} s for one fails (ActorTimeout)." if wait is not None else ""
        )
        return self.add_actor(
            name,
            subscribe,
            Kind.STREAM,
            buffer=qos_depth(qos),
            signature=inspect.Signature([]),
            hub_only=bus.delivers_on_hub,
            safety=Safety(read_only=True),  # listening changes nothing
            wait=wait,
            wait_detail=lambda seconds: silence(bus, t, msg_type, seconds),
        )

    def register_action(self, name: str, action_type: type[RosAction], server: str, *, moves: bool = False) -> ActorRef:
        """Make async actor ``name(goal)`` that sends a goal to action ``server``;
        ``moves``: the goal commands motion (see :class:`~bt_engine.actor.Safety`)."""
        return _declared(self._rt.bus.register_action(self, name, action_type, server), moves)

    def register_service(self, name: str, srv_type: type, server: str, *, moves: bool = False) -> ActorRef:
        """Make async actor ``name(request)`` that calls service ``server``."""
        return _declared(self._rt.bus.register_service(self, name, srv_type, server), moves)


def _declared(ref: ActorRef, moves: bool) -> ActorRef:
    """``ref`` marked as moving the robot when ``moves`` (the transports build the
    action and service actors, this is where their safety is declared)."""
    if moves:
        ref.safety = Safety(moves=True, limits=ref.safety.limits)
    return ref


def _wants_args(init: Callable, n: int) -> bool:
    """True when constructor ``init`` requires exactly ``n`` positional arguments."""
    try:
        params = list(inspect.signature(init).parameters.values())[1:]  # skip self
    except (TypeError, ValueError):
        return False
    required = [p for p in params if p.default is p.empty and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    return len(required) == n


def _topic(topic: str) -> str:
    return topic if topic.startswith("/") else "/" + topic


class SubNet(CallApi):
    """A group of actors included into a SubSystem with ``add_network``.

    It keeps no state of its own: values, calls and edges go to its SubSystem.
    """

    _subsystem: SubSystem

    def __init__(self, subsystem: "SubSystem | None" = None) -> None:
        # ``subsystem`` exists only for ros_actor-style SubNets that pass it on.
        pass

    @property
    def _rt(self) -> Any:
        return self._subsystem._rt

    def _txns(self) -> TransactionTable:
        return self._subsystem._rt.txns

    def _call_scope(self) -> SubSystem:
        return self._subsystem

    @property
    def subsystem(self) -> SubSystem:
        return self._subsystem

    def get_value(self, key: str, default: Any = _MISSING) -> Any:
        return self._subsystem.get_value(key, default)

    def set_value(self, key: str, value: Any) -> None:
        self._subsystem.set_value(key, value)
