"""Located XML: elements that remember where they and each attribute value start.

``xml.etree`` forgets positions, so the file is read with ``xml.parsers.expat``
directly. Attribute positions are found by scanning the start tag's text from the
element's byte offset. Documents with a DOCTYPE are refused (no entity tricks), and a
file that is not well-formed XML gives a located :class:`XmlSyntaxError`, never a
traceback.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from ._errors import Pos, XmlSyntaxError

__all__ = ["MAX_XML_SIZE", "XElement", "parse_xml", "read_xml"]

#: Largest XML file read [bytes]; Nav2's largest navigator is ~10 kB.
MAX_XML_SIZE = 2_000_000


@dataclass(eq=False)
class XElement:
    """One XML element.

    Attributes:
        tag: the element name.
        attrs: attribute values, in document order.
        pos: where the ``<`` of its start tag is.
        attr_pos: where each attribute's value starts (after the quote).
        children: child elements (text and comments are dropped).
        text: the text directly inside it, stripped.
    """

    tag: str
    attrs: dict[str, str]
    pos: Pos
    attr_pos: dict[str, Pos] = field(default_factory=dict)
    children: list["XElement"] = field(default_factory=list)
    text: str = ""

    def at(self, attr: str) -> Pos:
        """Where an attribute's value starts, or the element's position."""
        return self.attr_pos.get(attr, self.pos)

    def value_pos(self, attr: str, offset: int) -> Pos:
        """Position of character ``offset`` of an attribute's value (exact when the value
        has no entity references before it, else its start)."""
        pos = self.attr_pos.get(attr)
        if pos is None:
            return self.pos
        raw = self.raw_values.get(attr, "")
        if "&" in raw[:offset] or "\n" in raw[:offset]:
            return pos
        return pos.shifted(offset)

    raw_values: dict[str, str] = field(default_factory=dict)


_ATTR = re.compile(rb"""\s+([^\s=/>]+)\s*=\s*()("[^"]*"|'[^']*')""")


def _column(data: bytes, line_start: int, index: int) -> int:
    return len(data[line_start:index].decode("utf-8", "replace")) + 1


def parse_xml(data: bytes, file: str) -> XElement:
    """Parse XML bytes into located elements.

    Raises:
        XmlSyntaxError: not well-formed, a DOCTYPE, or larger than MAX_XML_SIZE.
    """
    if len(data) > MAX_XML_SIZE:
        raise XmlSyntaxError(Pos(file, 1, 1), f"file larger than {MAX_XML_SIZE} bytes, expected a behaviour tree")
    line_starts = [0] + [m.end() for m in re.finditer(rb"\n", data)]
    parser = expat.ParserCreate()
    parser.ordered_attributes = False
    stack: list[XElement] = []
    top: list[XElement] = []
    texts: list[list[str]] = []

    def pos_of(index: int) -> Pos:
        line = data.count(b"\n", 0, index) + 1
        return Pos(file, line, _column(data, line_starts[line - 1], index))

    def start(tag: str, attrs: dict[str, str]) -> None:
        index = parser.CurrentByteIndex
        element = XElement(tag, dict(attrs), pos_of(index))
        cursor = index + 1 + len(tag.encode("utf-8"))
        while True:  # attribute by attribute: a quoted value may hold '>'
            m = _ATTR.match(data, cursor)
            if m is None:
                break
            name = m.group(1).decode("utf-8", "replace")
            value_index = m.start(3) + 1
            if name in attrs and name not in element.attr_pos:
                element.attr_pos[name] = pos_of(value_index)
                element.raw_values[name] = m.group(3)[1:-1].decode("utf-8", "replace")
            cursor = m.end()
        if stack:
            stack[-1].children.append(element)
        else:
            top.append(element)
        stack.append(element)
        texts.append([])

    def end(tag: str) -> None:
        element = stack.pop()
        element.text = "".join(texts.pop()).strip()

    def chars(text: str) -> None:
        if texts:
            texts[-1].append(text)

    def doctype(*_args: object) -> None:
        raise XmlSyntaxError(
            pos_of(parser.CurrentByteIndex), "a DOCTYPE is not accepted, expected a plain BehaviorTree.CPP XML file"
        )

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = chars
    parser.StartDoctypeDeclHandler = doctype
    try:
        parser.Parse(data, True)
    except expat.ExpatError as exc:
        message = expat.ErrorString(exc.code)
        hint = {
            "mismatched tag": "expected the closing tag of the element opened before",
            "not well-formed (invalid token)": (
                "expected well-formed XML (write & as &amp; and < as &lt; in attributes)"
            ),
            "unclosed token": "expected the element or attribute to be closed",
            "no element found": "expected a <root> element",
            "junk after document element": "expected a single <root> element",
        }.get(message, "expected well-formed XML")
        line_start = line_starts[exc.lineno - 1] if exc.lineno - 1 < len(line_starts) else 0
        column = _column(data, line_start, min(line_start + exc.offset, len(data)))
        raise XmlSyntaxError(Pos(file, exc.lineno, column), f"not well-formed XML: {message}, {hint}") from None
    if not top:
        raise XmlSyntaxError(Pos(file, 1, 1), "no element found, expected a <root> element")
    return top[0]


def read_xml(path: str | Path) -> XElement:
    """Read and parse an XML file (see :func:`parse_xml`).

    Raises:
        XmlSyntaxError: unreadable, too large or not well-formed.
    """
    file = str(path)
    try:
        with open(path, "rb") as stream:
            data = stream.read(MAX_XML_SIZE + 1)
    except (OSError, ValueError) as exc:
        raise XmlSyntaxError(
            Pos(file, 1, 1), f"cannot read XML file: {getattr(exc, 'strerror', None) or exc}"
        ) from None
    return parse_xml(data, file)
