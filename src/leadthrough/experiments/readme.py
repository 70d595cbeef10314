"""The README's generated parts: tables and numbers that ``make docs`` writes, between markers.

A table (or any block) generated into ``docs/results/NAME.md`` appears in the README as::

    <!-- begin docs/results/NAME.md -->
    ...the file's content...
    <!-- end docs/results/NAME.md -->

and a number from ``docs/results/numbers.json`` (a mapping of keys to the text shown) as
``<!-- n:KEY -->0.89<!-- /n -->``. :func:`rewrite` puts the generated content between the
markers; :func:`stale` lists every place where the README differs from the generated files
(the test that keeps the README true calls it, no simulation needed). HTML comments do not
show in rendered Markdown.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

BLOCK = re.compile(r"(<!-- begin (docs/results/[\w.-]+\.md) -->\n)(.*?)(<!-- end \2 -->)", re.S)
NUMBER = re.compile(r"(<!-- n:([\w.-]+) -->)(.*?)(<!-- /n -->)")
#: The numbers file, relative to the repository root.
NUMBERS = "docs/results/numbers.json"


def _numbers(root: Path) -> dict[str, str]:
    path = root / NUMBERS
    return json.loads(path.read_text(encoding="utf-8")) if path.exists() else {}


def _block(root: Path, name: str) -> str | None:
    path = root / name
    return path.read_text(encoding="utf-8").rstrip("\n") + "\n" if path.exists() else None


def rewrite(text: str, root: Path) -> str:
    """``text`` with every marked block and number replaced by its generated content.

    Markers whose file or key does not exist are left as they are (:func:`stale` reports
    them).
    """
    numbers = _numbers(root)

    def block(match: re.Match[str]) -> str:
        content = _block(root, match[2])
        return match[0] if content is None else match[1] + content + match[4]

    def number(match: re.Match[str]) -> str:
        value = numbers.get(match[2])
        return match[0] if value is None else match[1] + value + match[4]

    return NUMBER.sub(number, BLOCK.sub(block, text))


def stale(text: str, root: Path) -> list[str]:
    """Every marked block or number of ``text`` that differs from the generated files."""
    numbers, problems = _numbers(root), []
    for match in BLOCK.finditer(text):
        content = _block(root, match[2])
        if content is None:
            problems.append(f"{match[2]}: no such generated file")
        elif match[3] != content:
            problems.append(f"{match[2]}: the README's copy differs (run make docs)")
    for match in NUMBER.finditer(text):
        if match[2] not in numbers:
            problems.append(f"number {match[2]}: not in {NUMBERS}")
        elif match[3] != numbers[match[2]]:
            problems.append(f"number {match[2]}: README {match[3]!r}, generated "
                            f"{numbers[match[2]]!r} (run make docs)")  # fmt: skip
    return problems


def update_readme(readme: Path, root: Path) -> bool:
    """Rewrite the generated parts of ``readme`` in place; whether anything changed."""
    text = readme.read_text(encoding="utf-8")
    new = rewrite(text, root)
    if new != text:
        readme.write_text(new, encoding="utf-8")
    return new != text
