"""Plain-words advice for YAML syntax errors.

PyYAML says what its parser expected (``expected <block end>, but found '-'``), which
is exact but speaks of tokens. Every loader of a user file (missions, worlds,
actorbt.yaml, goal inputs) adds the likely fix from :func:`syntax_message`, in words a
newcomer can act on. The advice is a guess from the parser's problem and context; when
no rule fits, a general hint names what usually causes the error.
"""

from __future__ import annotations

import re

import yaml

#: what most YAML syntax errors come from, when no specific rule fits
GENERAL_HINT = (
    "check this line and the one above it: the indentation, a missing ': ' after a key, or a quote or bracket left open"
)


def _line(mark: yaml.Mark | None) -> int | None:
    return mark.line + 1 if mark is not None else None


def syntax_hint(exc: yaml.MarkedYAMLError) -> str:
    """The likely fix for ``exc``, in plain words."""
    problem = exc.problem or ""
    context = exc.context or ""
    here = _line(exc.problem_mark)
    start = _line(exc.context_mark) or here
    since = f" (the block starting at line {start})" if start is not None and start != here else ""

    if "'\\t'" in problem:
        return "YAML indents with spaces only: replace the tab on this line with spaces"
    found = re.search(r"found character '(.)' that cannot start any token", problem)
    if found:
        return f"a plain value cannot start with '{found.group(1)}' in YAML: put the value in quotes"
    if "quoted scalar" in context:
        return (
            f"the quoted text opened at line {start} is never closed: add the closing quote "
            "(or escape a quote inside it)"
        )
    if "flow sequence" in context:
        return (
            f"the [list] opened at line {start} is not closed, or two of its items lack a ',' "
            "between them: check its brackets and commas"
        )
    if "flow mapping" in context:
        return (
            f"the {{mapping}} opened at line {start} is not closed, or two of its entries lack a ',' "
            "between them: check its braces and commas"
        )
    if "another document" in problem:
        return "the file holds one document: remove this '---' line, or put the second part in a file of its own"
    if "alias" in context or "undefined alias" in problem:
        return "'*' starts an alias in YAML: put the value in quotes"
    if "<stream end>" in problem or "end of stream" in problem:
        return "the text ends inside a value: close the bracket, brace or quote opened before it"
    if "could not find expected ':'" in problem:
        return (
            f"line {start} is not a 'key: value' line: add ': ' after its key, or indent it as part of the value above"
        )
    if problem.startswith("expected <block end>"):
        if "'-'" in problem or "<block sequence start>" in problem:
            return (
                f"check the indentation of this line against the line above{since}: the '-' items of "
                "one list start in the same column, and a list under a key is indented more than the key"
            )
        if "<block mapping start>" in problem:
            return (
                f"check the indentation of this line against the line above{since}: the keys of one "
                "mapping start in the same column"
            )
        if "<scalar>" in problem:
            return (
                "a value continues after its end on this line: quote the whole value, or move the rest to its own line"
            )
        return f"check the indentation of this line against the line above{since}"
    if "did not find expected key" in problem:
        return (
            f"check the indentation of this line against the keys above it{since}: "
            "keys of one mapping start in the same column"
        )
    if "did not find expected '-' indicator" in problem:
        return f"this line is not in line with the list items above it{since}: start it with '- ' in the items' column"
    if "mapping values are not allowed here" in problem:
        return (
            "a ':' where no key can start: if the ':' belongs to a value, put the value in quotes; "
            "if this line is a key, check its indentation and that the line above ends with its value "
            "(is a ':' missing there?)"
        )
    return GENERAL_HINT


#: the parser's names of what it met, in words
_TOKENS = {
    "'?'": "a key",
    "<block mapping start>": "a key",
    "'-'": "a '-' item",
    "<block sequence start>": "a '-' item",
    "<scalar>": "a value",
    "<stream end>": "the end of the text",
    "<block end>": "the end of the block above",
    "<document start>": "a new document",
    "<anchor>": "an '&' anchor",
    "<alias>": "a '*' alias",
    "<tag>": "a '!' tag",
}


def _words(token: str) -> str:
    token = token.strip()
    if token.startswith("'<") and token.endswith(">'"):
        token = token[1:-1]
    return _TOKENS.get(token, token if token.startswith("'") else f"'{token}'")


def syntax_problem(exc: yaml.MarkedYAMLError) -> str:
    """What the parser met, in words rather than its token names (``found '?'`` is a key)."""
    problem = exc.problem or "invalid YAML"
    met = re.match(r"(?:did not find )?expected (.+?), but (?:found|got) (.+)$", problem)
    if met:
        wanted = " or ".join(_words(t) for t in re.split(r" or ", met.group(1)))
        return f"{_words(met.group(2))} where {wanted} was expected"
    for raw, words in (
        ("mapping values are not allowed here", "a ':' after a value"),
        ("could not find expected ':'", "a line with no ': ' after its key"),
        ("found unexpected end of stream", "the text ends inside a quoted value"),
        ("found undefined alias", "a '*' alias that names no anchor"),
        ("but found another document", "a second document ('---') in one file"),
    ):
        if problem.startswith(raw):
            return words
    char = re.search(r"found character '(.+?)' that cannot start any token", problem)
    if char:
        return f"'{char.group(1)}' cannot start a value" if char.group(1) != "\\t" else "a tab character"
    return problem


def syntax_message(exc: yaml.MarkedYAMLError) -> str:
    """``YAML syntax error: <what the parser met, in words>; <the likely fix>`` (no
    position: the caller puts ``file:line:column`` in front)."""
    return f"YAML syntax error: {syntax_problem(exc)}; {syntax_hint(exc)}"


def syntax_mark(exc: yaml.MarkedYAMLError) -> yaml.Mark | None:
    """Where to point: the problem's position, except for an unclosed quote, whose
    problem is the end of the file; there it is where the quote opens."""
    if "quoted scalar" in (exc.context or "") and exc.context_mark is not None:
        return exc.context_mark
    return exc.problem_mark or exc.context_mark
