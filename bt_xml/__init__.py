"""BehaviorTree.CPP v4 XML (and pytwb's XML) imported as actorbt missions, missions
exported as BehaviorTree.CPP XML, and traces converted to Groot2 logs.

Layering: part of ``bt_engine``; it builds on the tree layer (``bt_engine.trees``) and
imports nothing robot-specific. Inside the package::

    _errors   BtXmlError and its subclasses (located, like mission errors)
    _source   located XML parsing with expat (line and column of every attribute)
    _nodes    the node model (<TreeNodesModel>): kinds, typed ports, actor signatures
    _script   BehaviorTree.CPP scripts -> set: values and check: expressions
    _values   port text <-> mission values (references, json:, typed literals)
    _builtins BehaviorTree.CPP's built-in nodes (and Nav2's controls) -> mission nodes
    _extensions  actorbt's own XML nodes, for what the built-ins cannot say
    _convert  BehaviorTree.CPP XML -> mission dicts
    _pytwb    the pytwb dialect (py_trees class names, Python literals)
    _api      import_files: dialect, files, conversion
    _emit     mission dicts -> YAML files
    _script_out  check: and set: -> BehaviorTree.CPP scripts, when exact
    _export   missions -> BehaviorTree.CPP XML with a node model from the catalog
    _compare  whether two missions are the same tree (the round trip's measure)
    _btlog    traces -> Groot2 logs (FileLogger2's .btlog)
    cli       actorbt xml import | export | btlog
"""

from ._api import DIALECTS, import_files
from ._btlog import BtlogError, trace_to_btlog, write_btlog
from ._compare import mission_differences
from ._convert import Importer, TreeInterface
from ._emit import dump_mission, write_missions
from ._errors import BtXmlError, UnknownXmlNodeError, UnsupportedXmlError, XmlSyntaxError
from ._export import ExportError, Exporter, export_tree
from ._nodes import ModelResolver, NodeKind, NodeModel, NodeSpec, PortDirection, PortSpec, read_node_model
from ._pytwb import PytwbImporter
from ._source import XElement, parse_xml, read_xml

__all__ = [
    "DIALECTS",
    "BtXmlError",
    "BtlogError",
    "ExportError",
    "Exporter",
    "Importer",
    "ModelResolver",
    "NodeKind",
    "NodeModel",
    "NodeSpec",
    "PortDirection",
    "PortSpec",
    "PytwbImporter",
    "TreeInterface",
    "UnknownXmlNodeError",
    "UnsupportedXmlError",
    "XElement",
    "XmlSyntaxError",
    "dump_mission",
    "export_tree",
    "import_files",
    "mission_differences",
    "parse_xml",
    "read_node_model",
    "read_xml",
    "trace_to_btlog",
    "write_btlog",
    "write_missions",
]
