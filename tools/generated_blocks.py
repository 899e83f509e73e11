"""Blocks of a Markdown document written by a tool: the lines between `<!-- KIND:NAME -->` and
`<!-- /KIND:NAME -->` (each marker on a line of its own, the closing one indented as the opening
one, which may sit inside a list item) are made again from their source; the rest is left as is.

Shared by tools/readme_figures.py (KIND figures) and tools/architecture_tables.py (KIND generated)."""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Callable


class BlocksError(Exception):
    """A document or a block's source is not as the tool expects (one line, for the user)."""


def rewrite_blocks(text: str, kind: str, render: dict[str, Callable[[], list[str]]]) -> tuple[str, list[str]]:
    """`text` with every KIND block made again by `render[name]()`, and the names of those that changed."""
    marker = re.compile(rf"^([ \t]*)(<!-- {kind}:([a-z0-9-]+) -->\n)(.*?)^(\1<!-- /{kind}:\3 -->)", re.S | re.M)
    opened = re.findall(rf"<!-- {kind}:([a-z0-9-]+) -->", text)
    closed = re.findall(rf"<!-- /{kind}:([a-z0-9-]+) -->", text)
    if sorted(opened) != sorted(closed) or len(set(opened)) != len(opened):
        raise BlocksError(f"unpaired or repeated {kind} markers: opened {opened}, closed {closed}")
    unknown = sorted(set(opened) - set(render))
    if unknown:
        raise BlocksError(f"unknown {kind} block(s) {unknown}; known: {sorted(render)}")
    changed = []

    def replace(match: re.Match) -> str:
        indent, name = match.group(1), match.group(3)
        body = "".join((indent + line).rstrip() + "\n" for line in render[name]())
        if body != match.group(4):
            changed.append(name)
        return indent + match.group(2) + body + match.group(5)

    new = marker.sub(replace, text)
    found = [match.group(3) for match in marker.finditer(text)]
    if sorted(found) != sorted(opened):
        raise BlocksError(f"a {kind} marker is not on a line of its own, or its closing marker is indented"
                          f" otherwise: {sorted(set(opened) - set(found))}")
    return new, changed


def update(tool: str, document: Path, kind: str, render: dict, check: bool, make_target: str,
           problems: Callable[[str], list[str]] = lambda text: []) -> int:
    """Rewrite `document`'s blocks (or with `check`, only say whether they are current): 0 when
    current and without `problems` (each printed), 1 when not, 2 when the blocks cannot be made."""
    try:
        text = document.read_text(encoding="utf-8")
        new, changed = rewrite_blocks(text, kind, render)
    except (BlocksError, OSError) as error:
        print(f"{tool}: {error}", file=sys.stderr)
        return 2
    found = problems(new)
    for problem in found:
        print(f"{tool}: {document.name}: {problem}", file=sys.stderr)
    blocks = len(re.findall(rf"<!-- {kind}:", text))
    if check:
        if changed:
            print(f"{tool}: {document} is out of date in {', '.join(changed)}; run `make {make_target}`",
                  file=sys.stderr)
            return 1
        print(f"{tool}: {document} is up to date ({blocks} blocks)")
    elif changed:
        document.write_text(new, encoding="utf-8")
        print(f"{tool}: rewrote {', '.join(changed)} in {document}")
    else:
        print(f"{tool}: {document} already up to date ({blocks} blocks)")
    return 1 if found else 0
