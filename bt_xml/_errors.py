"""Errors of the XML importer. Each points at ``file.xml:line:column`` like the mission
loader's errors (they are :class:`~bt_engine.trees.MissionError` subclasses)."""

from __future__ import annotations

from bt_engine.trees import MissionError, Pos

__all__ = ["BtXmlError", "Pos", "UnknownXmlNodeError", "UnsupportedXmlError", "XmlSyntaxError"]


class BtXmlError(MissionError):
    """An XML behaviour tree (or node model) cannot be imported; the root of this package's errors."""


class XmlSyntaxError(BtXmlError):
    """The file is not well-formed XML, or uses what the importer refuses (a DOCTYPE)."""


class UnknownXmlNodeError(BtXmlError):
    """A tag names no built-in node, tree or node of the model (close matches offered)."""


class UnsupportedXmlError(BtXmlError):
    """A construct that has no equivalent in actorbt missions (see docs/btxml.md)."""
