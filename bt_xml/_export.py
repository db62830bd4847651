"""Missions exported as BehaviorTree.CPP v4 XML that Groot2 opens and edits, and that
``actorbt xml import`` reads back as the same missions (the inverse of ``_convert``).

- A tree and every tree it calls become ``<BehaviorTree ID>`` elements; a call of a tree
  is ``<SubTree ID="t" input="{key}" result="{key}"/>``, where the output port of type
  :data:`~._values.RESULT_TYPE` receives the whole result mapping (``out:``).
- Controls and decorators become BehaviorTree.CPP's built-ins (Nav2's for
  ``pipeline_sequence``, ``recovery``, ``rate_controller``); what has none becomes one of
  actorbt's own nodes (:mod:`._extensions`).
- An actor call is a leaf named after the actor: its arguments are input ports, its
  result is an output port (``result`` unless a parameter has that name).
- ``<TreeNodesModel>`` declares every actor (from the catalog: typed ports, defaults and
  descriptions), every tree (its inputs and outputs, its doc) and every non-built-in node
  used.

Values are written as :mod:`._values` says.
"""

from __future__ import annotations

import inspect
import math
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Any, Callable

from bt_engine.errors import ActorbtError
from bt_engine.trees import (
    UNSET,
    Check,
    Condition,
    Do,
    ForceFailure,
    ForceSuccess,
    IfThenElse,
    InputPort,
    Invert,
    Mission,
    Node,
    Parallel,
    ParallelPolicy,
    PipelineSequence,
    PluginNode,
    PluginSpec,
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
    TreeLibrary,
    UseBehaviour,
    Wait,
    WhileDoElse,
    annotation_text,
    children_of,
)
from ._builtins import BUILTINS, NAV2, UNSUPPORTED
from ._errors import BtXmlError
from ._extensions import EXTENSIONS, LIST_SEPARATOR, NAV2_MODELS, NodeDecl, PortDecl
from ._script_out import check_script, set_script
from ._values import RESULT_TYPE, encode_value, port_type

__all__ = ["ExportError", "Exporter", "export_tree"]

_PORT_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
_RESERVED = {"name", "ID", "_autoremap"}
_SELECTORS = (Selector, ReactiveSelector)
_SIMPLE = {
    Sequence: "Sequence",
    ReactiveSequence: "ReactiveSequence",
    Selector: "Fallback",
    ReactiveSelector: "ReactiveFallback",
    ResumeSequence: "SequenceWithMemory",
    PipelineSequence: "PipelineSequence",
    IfThenElse: "IfThenElse",
    WhileDoElse: "WhileDoElse",
    Invert: "Inverter",
    ForceSuccess: "ForceSuccess",
    ForceFailure: "ForceFailure",
}


class ExportError(BtXmlError):
    """A mission cannot be written as BehaviorTree.CPP XML; located in the mission file."""


@dataclass
class LeafModel:
    """The ``<TreeNodesModel>`` entry of an actor or a tree, filled while exporting."""

    kind: str
    id: str
    description: str
    ports: dict[str, PortDecl] = field(default_factory=dict)
    result_port: str = "result"


Resolver = Callable[[str], Any]


class Exporter:
    """Writes missions of a library (validated) as one BehaviorTree.CPP v4 document.

    Args:
        library: the trees; a tree is exported with every tree it calls.
        resolve: the actor catalog (``name -> actor info`` with a signature, and a
            ``tool`` description when it has one); ``None``: the ports are the
            arguments the trees pass, untyped.
    """

    def __init__(self, library: TreeLibrary, resolve: Resolver | None = None) -> None:
        self.library = library
        self.resolve = resolve
        self.models: dict[str, LeafModel] = {}
        self.declared: dict[str, NodeDecl] = {}

    # ------------------------------------------------------------ document

    def trees_of(self, name: str) -> list[Mission]:
        """``name`` and every library tree it calls, directly or not, main tree first."""
        order: list[str] = []
        todo = [name]
        while todo:
            current = todo.pop(0)
            if current in order:
                continue
            order.append(current)
            todo.extend(
                n.actor
                for n in _walk(self.library[current].root)
                if isinstance(n, Do) and n.actor in self.library and n.actor not in order
            )
        return [self.library[n] for n in order]

    def document(self, name: str) -> ET.Element:
        """The ``<root>`` element: the trees, then the node model."""
        root = ET.Element("root", {"BTCPP_format": "4", "main_tree_to_execute": name})
        for mission in self.trees_of(name):
            if mission.name not in self.models:
                self.models[mission.name] = _tree_model(mission)
            tree = ET.SubElement(root, "BehaviorTree", {"ID": mission.name})
            tree.append(self.subtree_xml(mission.root, None))
        root.append(self.model_xml())
        return root

    def subtree_xml(self, node: Node, parent: Node | None) -> ET.Element:
        element = self.element(node, parent)
        for child in children_of(node):
            element.append(self.subtree_xml(child, node))
        return element

    # ------------------------------------------------------------ nodes

    def element(self, node: Node, parent: Node | None) -> ET.Element:
        """The XML element of one mission node, without its children."""
        tag, attrs = self.tag_and_ports(node, parent)
        element = ET.Element(tag)
        if tag == "SubTree":
            element.set("ID", attrs.pop("ID"))
        if node.name is not None:
            element.set("name", node.name)
        elif not _label_kept(node, tag, attrs):
            element.set("name", node.label)  # the label (and trace paths) of the node read back
        for key, value in attrs.items():
            element.set(key, value)
        return element

    def tag_and_ports(self, node: Node, parent: Node | None) -> tuple[str, dict[str, str]]:
        kind = type(node)
        if kind in _SIMPLE:
            return self.use(_SIMPLE[kind]), {}
        if isinstance(node, Parallel):
            return self.parallel(node)
        if isinstance(node, Recovery):
            return self.use("RecoveryNode"), {"number_of_retries": encode_value(node.retries, "int")}
        if isinstance(node, Retry):
            attempts = "-1" if node.times is None else encode_value(node.times, "int")
            return "RetryUntilSuccessful", {"num_attempts": attempts}
        if isinstance(node, Repeat):
            return "Repeat", {"num_cycles": "-1" if node.times is None else encode_value(node.times, "int")}
        if isinstance(node, Timeout):
            msec = _msec(node.seconds)
            if msec is None:
                return self.use("ActorbtTimeout"), {"seconds": encode_value(node.seconds, "double")}
            return "Timeout", {"msec": msec}
        if isinstance(node, Wait):
            msec = _msec(node.seconds)
            if msec is None:
                return self.use("ActorbtWait"), {"seconds": encode_value(node.seconds, "double")}
            return "Sleep", {"msec": msec}
        if isinstance(node, RateController):
            return self.use("RateController"), {"hz": encode_value(node.hz, "double")}
        if isinstance(node, RunOnce):
            return self.run_once(node, parent)
        if isinstance(node, Check):
            script = check_script(node)
            if script is None:
                return self.use("ActorbtCheck"), {"expr": node.source}
            return "ScriptCondition", {"code": script}
        if isinstance(node, SetValues):
            return self.set_values(node)
        if isinstance(node, UseBehaviour):
            attrs = {"behaviour": node.behaviour}
            if node.kwargs:
                attrs["with"] = encode_value(dict(node.kwargs), "dict")
            if node.writes:
                attrs["writes"] = LIST_SEPARATOR.join(node.writes)
            return self.use("ActorbtBehaviour"), attrs
        if isinstance(node, PluginNode):
            return self.plugin(node)
        if isinstance(node, Do):
            return self.call(node)
        raise ExportError(node.pos, f"a {node.kind} node has no BehaviorTree.CPP form")  # pragma: no cover

    def use(self, node_id: str) -> str:
        """A node that is not built in: declared in the model."""
        decl = EXTENSIONS.get(node_id) or NAV2_MODELS.get(node_id)
        if decl is not None:
            self.declared[node_id] = decl
        return node_id

    def parallel(self, node: Parallel) -> tuple[str, dict[str, str]]:
        if node.counted:
            return "Parallel", {
                "success_count": str(node.success_count if node.success_count is not None else -1),
                "failure_count": str(node.failure_count if node.failure_count is not None else 1),
            }
        if node.policy is ParallelPolicy.SUCCESS_ON_ONE:
            return "Parallel", {"success_count": "1", "failure_count": "1"}
        if node.policy is ParallelPolicy.SUCCESS_ON_ALL:
            return "Parallel", {"success_count": "-1", "failure_count": "1"}
        bad = next((n for n in node.selected if LIST_SEPARATOR in n), None)
        if bad is not None:
            raise ExportError(
                node.at("selected"),
                f"selected child {bad!r} has a {LIST_SEPARATOR!r} in its name, expected names without one",
            )
        return self.use("ActorbtParallel"), {"selected": LIST_SEPARATOR.join(node.selected)}

    def run_once(self, node: RunOnce, parent: Node | None) -> tuple[str, dict[str, str]]:
        in_selector = isinstance(parent, _SELECTORS)
        # BehaviorTree.CPP's RunOnce skips after the first run; the importer reads a skip
        # as a failure under a selector and as a success elsewhere
        if node.then is RunOnceThen.SAME:
            return "RunOnce", {"then_skip": "false"}
        if node.then is RunOnceThen.SUCCESS and not in_selector or node.then is RunOnceThen.FAILURE and in_selector:
            return "RunOnce", {"then_skip": "true"}
        if node.then is RunOnceThen.FAILURE:
            return self.use("SingleTrigger"), {}
        return self.use("ActorbtRunOnce"), {"then": node.then.value.upper()}

    def plugin(self, node: PluginNode) -> tuple[str, dict[str, str]]:
        """A control or decorator written in Python: a node of its name, its ports as
        attributes, declared in the model with the plugin's ports (``xml import`` reads
        it back as the same plugin call)."""
        spec = self.library.nodes.get(node.plugin)
        if spec is not None:
            self.declared[node.plugin] = _plugin_decl(spec)
        if node.plugin in BUILTINS or node.plugin in NAV2 or node.plugin in EXTENSIONS:
            raise ExportError(
                node.at(node.kind),
                f"{node.kind} {node.plugin!r} has the name of a BehaviorTree.CPP "
                "node, expected a plugin named otherwise",
            )
        attrs: dict[str, str] = {}
        for name, value in node.ports.items():
            port = spec.ports.get(name) if spec is not None else None
            attrs[name] = encode_value(value, _cpp_type(port.type) if port is not None else "")
        for name, key in node.outs.items():
            attrs[name] = "{" + key + "}"
        return node.plugin, attrs

    def set_values(self, node: SetValues) -> tuple[str, dict[str, str]]:
        if len(node.values) == 1:
            [(key, value)] = node.values.items()
            return "SetBlackboard", {"value": encode_value(value), "output_key": key}
        script = set_script(node)
        if script is not None:
            return "Script", {"code": script}
        return self.use("ActorbtSet"), {"values": encode_value(dict(node.values), "dict")}

    # ------------------------------------------------------------ calls

    def call(self, node: Do) -> tuple[str, dict[str, str]]:
        tree = node.actor in self.library
        model = self.model_of(node)
        kwargs = self.keywords(node, model)
        attrs: dict[str, str] = {}
        for name, value in kwargs.items():
            if not _PORT_NAME.match(name) or name in _RESERVED:
                raise ExportError(
                    node.arg_pos.get(name, node.pos),
                    f"argument {name!r} of {node.actor!r} cannot be a BehaviorTree.CPP port name, "
                    "expected a name that starts with a letter and is not 'name' or 'ID'",
                )
            port = model.ports.get(name)
            if port is None:  # an argument the catalog does not list (**kwargs)
                port = model.ports[name] = PortDecl("input_port", name, "", "")
            attrs[name] = encode_value(value, port.type)
        if node.out is not None:
            if model.result_port not in model.ports:
                _add_result(model)
            attrs[model.result_port] = "{" + node.out + "}"
        if tree:
            return "SubTree", {"ID": node.actor, **attrs}
        if model.kind != _leaf_kind(node):  # the actor is also used the other way: say which
            return _leaf_kind(node), {"ID": node.actor, **attrs}
        if (
            node.actor in BUILTINS
            or node.actor in NAV2
            or node.actor in UNSUPPORTED
            or node.actor in EXTENSIONS
            or node.actor in ("SubTree", "BehaviorTree", "root", "include", "TreeNodesModel")
        ):
            raise ExportError(
                node.at(node.kind),
                f"actor {node.actor!r} has the name of a BehaviorTree.CPP node, expected an actor named otherwise",
            )
        return node.actor, attrs

    def keywords(self, node: Do, model: LeafModel) -> dict[str, Any]:
        """The call's arguments by name (positional ones named by the signature)."""
        if not node.args:
            return dict(node.kwargs)
        signature = self.signature(node.actor)
        names = (
            [p.name for p in signature.parameters.values() if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
            if signature is not None
            else []
        )
        if len(names) < len(node.args):
            raise ExportError(
                node.at("with"),
                f"{node.actor!r} is called with {len(node.args)} positional "
                f"arguments, but only {len(names)} parameters have a name that a "
                "port can take, expected keyword arguments (with: {name: value})",
            )
        return {**dict(zip(names, node.args)), **node.kwargs}

    def signature(self, actor: str) -> inspect.Signature | None:
        if actor in self.library:
            return self.library[actor].signature()
        info = self.info(actor)
        return getattr(info, "signature", None) if info is not None else None

    def info(self, actor: str) -> Any:
        if self.resolve is None:
            return None
        try:
            return self.resolve(actor)
        except (LookupError, ActorbtError):  # unknown or ambiguous: the check reports it
            return None

    def model_of(self, node: Do) -> LeafModel:
        model = self.models.get(node.actor)
        if model is not None:
            return model
        if node.actor in self.library:
            model = _tree_model(self.library[node.actor])
        else:
            model = _actor_model(node.actor, self.info(node.actor), _leaf_kind(node))
        self.models[node.actor] = model
        return model

    # ------------------------------------------------------------ node model

    def model_xml(self) -> ET.Element:
        models = ET.Element("TreeNodesModel")
        entries: list[tuple[str, str, str, list[PortDecl]]] = []
        for decl in self.declared.values():
            entries.append((decl.kind, decl.id, decl.description, list(decl.ports)))
        for model in self.models.values():
            entries.append((model.kind, model.id, model.description, list(model.ports.values())))
        for kind, node_id, description, ports in sorted(entries, key=lambda e: e[1]):
            element = ET.SubElement(models, kind, {"ID": node_id})
            for port in ports:
                attrs = {"name": port.name}
                if port.type:
                    attrs["type"] = port.type
                if port.default is not None:
                    attrs["default"] = port.default
                ET.SubElement(element, port.direction, attrs).text = port.description or None
            if description:
                ET.SubElement(element, "description").text = description
        return models


def _walk(node: Node) -> list[Node]:
    out = [node]
    for child in children_of(node):
        out.extend(_walk(child))
    return out


def _label_kept(node: Node, tag: str, attrs: dict[str, str]) -> bool:
    """Whether the importer gives an unnamed node the same label: a time or rate is read
    back as a float (from milliseconds for Sleep and Timeout), so ``wait 1s`` would
    become ``wait 1.0s``."""
    value = (
        getattr(node, "seconds", None)
        if isinstance(node, (Wait, Timeout))
        else getattr(node, "hz", None)
        if isinstance(node, RateController)
        else None
    )
    if value is None or isinstance(value, Ref):
        return True
    back = int(attrs["msec"]) * 0.001 if "msec" in attrs else float(next(iter(attrs.values())))
    return type(back) is type(value) and repr(back) == repr(value)


def _msec(seconds: float | Ref) -> str | None:
    """Whole milliseconds (BehaviorTree.CPP's Timeout and Sleep take an unsigned count),
    or None when the time is a reference or has a fraction of a millisecond."""
    if isinstance(seconds, Ref):
        return None
    msec = seconds * 1000.0
    whole = round(msec)
    if not math.isfinite(msec) or abs(msec - whole) > 1e-6 * max(1.0, abs(msec)):
        return None
    return str(whole)


def _result_port(taken: set[str]) -> str:
    for name in ("result", "out", "outputs", "returned"):
        if name not in taken:
            return name
    n = 1
    while f"result{n}" in taken:
        n += 1
    return f"result{n}"


def _tree_model(mission: Mission) -> LeafModel:
    model = LeafModel("SubTree", mission.name, (mission.doc or "").strip())
    for spec in mission.inputs:
        default = None if spec.required else encode_value(spec.default, port_type(spec.type), default=True)
        model.ports[spec.name] = PortDecl(
            "input_port", spec.name, port_type(spec.type), (spec.doc or "").strip(), default
        )
    for out in mission.outputs:
        if out.name in model.ports:
            raise ExportError(
                out.pos,
                f"{out.name!r} is both an input and an output of tree {mission.name!r}: "
                "BehaviorTree.CPP would need an inout port, expected another output name",
            )
        model.ports[out.name] = PortDecl("output_port", out.name, port_type(out.type), (out.doc or "").strip())
    for name, port in model.ports.items():
        if not _PORT_NAME.match(name) or name in _RESERVED:
            raise ExportError(
                mission.pos,
                f"tree {mission.name!r} has the port {name!r}, which BehaviorTree.CPP "
                "does not accept, expected a name that starts with a letter and is not "
                "'name' or 'ID'",
            )
    model.result_port = _result_port(set(model.ports))
    model.ports[model.result_port] = PortDecl(
        "output_port",
        model.result_port,
        RESULT_TYPE,
        "every output of the tree, as one mapping (what a mission's out: receives)",
    )
    return model


def _plugin_decl(spec: PluginSpec) -> NodeDecl:
    """A plugin's entry in the node model: its kind, typed ports and defaults."""
    ports = []
    for name, port in spec.ports.items():
        ptype = _cpp_type(port.type)
        if isinstance(port, InputPort):
            default = None
            if port.default is not UNSET:
                default = (
                    port.default
                    if isinstance(port.default, str) and port.default.startswith("{")
                    else encode_value(port.default, ptype, default=True)
                )
            ports.append(PortDecl("input_port", name, ptype, port.doc, default))
        else:
            ports.append(PortDecl("output_port", name, ptype, port.doc))
    return NodeDecl(spec.kind.capitalize(), spec.name, spec.doc.split("\n\n")[0].replace("\n", " "), tuple(ports))


def _leaf_kind(node: Do) -> str:
    """``condition:`` leaves are BehaviorTree.CPP Conditions (answered within the tick),
    ``do:`` leaves Actions."""
    return "Condition" if isinstance(node, Condition) else "Action"


def _actor_model(actor: str, info: Any, kind: str) -> LeafModel:
    tool = _tool(info)
    props = (tool.get("parameters") or {}).get("properties") or {}
    signature: inspect.Signature | None = getattr(info, "signature", None)
    returns = signature.return_annotation if signature is not None else inspect.Signature.empty
    model = LeafModel(kind, actor, (tool.get("description") or getattr(info, "doc", None) or "").strip())
    for param in signature.parameters.values() if signature is not None else ():
        if param.kind in (param.VAR_POSITIONAL, param.VAR_KEYWORD):
            continue
        prop = props.get(param.name) or {}
        ptype = _cpp_type(param.annotation)
        default = None
        if "default" in prop:
            default = encode_value(prop["default"], ptype, default=True)
        elif param.default is not param.empty and _plain(param.default):
            default = encode_value(param.default, ptype, default=True)
        model.ports[param.name] = PortDecl("input_port", param.name, ptype, prop.get("description", ""), default)
    model.result_port = _result_port(set(model.ports))
    if _type_text(returns) not in ("", "None"):
        _add_result(model, _cpp_type(returns), (tool.get("returns") or {}).get("description", ""))
    return model


def _add_result(model: LeafModel, type_: str = "", description: str = "") -> None:
    model.ports[model.result_port] = PortDecl(
        "output_port", model.result_port, type_, description or "the actor's result"
    )


def _plain(value: Any) -> bool:
    if value is None or isinstance(value, (bool, int, float, str)):
        return True
    if isinstance(value, (list, tuple)):
        return all(_plain(v) for v in value)
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain(v) for k, v in value.items())
    return False


def _tool(info: Any) -> dict[str, Any]:
    tool = getattr(info, "tool", None)
    if isinstance(tool, dict):
        return tool
    if info is not None and hasattr(info, "impl") and hasattr(info, "path"):
        try:
            from bt_engine.catalog import tool_schema

            return tool_schema(info)
        except Exception:  # a description is a nicety; the ports come from the signature
            return {}
    return {}


_OPTIONAL = re.compile(r"(?:Optional\[(.*)\]|(.*?)\s*\|\s*None|None\s*\|\s*(.*))\Z")
_SCALARS = {"int": "int", "float": "double", "bool": "bool", "str": "std::string"}


def _type_text(annotation: Any) -> str:
    if annotation is inspect.Parameter.empty or annotation is None:
        return ""
    text = annotation_text(annotation)
    m = _OPTIONAL.match(text.strip())
    if m is not None:
        text = next(g for g in m.groups() if g is not None)
    return text.strip()


def _cpp_type(annotation: Any) -> str:
    """A parameter's port type: C++ names for the plain types BehaviorTree.CPP converts
    (``Optional`` dropped), the Python annotation's text otherwise, "" without one."""
    text = _type_text(annotation)
    return _SCALARS.get(text, text)


def export_tree(name: str, library: TreeLibrary, resolve: Resolver | None = None) -> str:
    """Tree ``name`` and the trees it calls as a BehaviorTree.CPP v4 XML document (text).

    Raises:
        KeyError: no tree of that name in the library.
        ExportError: something in a mission has no XML form (located in its file).
    """
    return _xml_text(Exporter(library, resolve).document(name))


def _xml_text(root: ET.Element) -> str:
    ET.indent(root, space="  ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
