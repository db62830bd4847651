"""BehaviorTree.CPP v4 XML (and pytwb's XML) imported as actorbt missions.

Layering: part of ``bt_engine``; it builds on the tree layer (``bt_engine.trees``) and
imports nothing robot-specific. Inside the package::

    _errors   BtXmlError and its subclasses (located, like mission errors)
    _source   located XML parsing with expat (line and column of every attribute)
    _nodes    the node model (<TreeNodesModel>): kinds, typed ports, actor signatures
    _script   BehaviorTree.CPP scripts -> set: values and check: expressions
    _convert  BehaviorTree.CPP XML -> mission dicts
    _pytwb    the pytwb dialect (py_trees class names, Python literals)
    _api      import_files: dialect, files, conversion
    _emit     mission dicts -> YAML files
    cli       actorbt xml import
"""

from ._api import DIALECTS, import_files
from ._convert import Importer, TreeInterface
from ._emit import dump_mission, write_missions
from ._errors import BtXmlError, UnknownXmlNodeError, UnsupportedXmlError, XmlSyntaxError
from ._nodes import ModelResolver, NodeKind, NodeModel, NodeSpec, PortDirection, PortSpec, read_node_model
from ._pytwb import PytwbImporter
from ._source import XElement, parse_xml, read_xml

__all__ = [
    "DIALECTS",
    "BtXmlError",
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
    "import_files",
    "parse_xml",
    "read_node_model",
    "read_xml",
    "write_missions",
]
