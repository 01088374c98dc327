#!/usr/bin/env python3
"""Checks the relative links of the README and the guide: every linked file exists, and every
#anchor names a heading of the page it points into (GitHub's rule for heading anchors).

    scripts/check_links.py            # README.md and every .md under docs/
    scripts/check_links.py FILE...    # just these

Prints each broken link as FILE:LINE: TARGET (why) and exits 1 if there is any; web links
(http, https, mailto) are not fetched. CI runs it.
"""

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LINK = re.compile(r"!?\[(?:[^\]\\]|\\.)*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
FENCE = re.compile(r"^\s*(```|~~~)")
CODE_SPAN = re.compile(r"`[^`]*`")


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    text = CODE_SPAN.sub(lambda m: m.group(0).strip("`"), heading.strip())
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link in a heading keeps its text
    text = text.lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def prose_lines(path: Path):
    """(line number, text) of the lines outside fenced code blocks."""
    fenced = False
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, line


def anchors(path: Path) -> set:
    found, seen = set(), {}
    for _, line in prose_lines(path):
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            base = slug(m.group(1))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
    return found


def broken_links(path: Path):
    for number, line in prose_lines(path):
        for m in LINK.finditer(CODE_SPAN.sub("", line)):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                continue  # a web address
            file_part, _, anchor = target.partition("#")
            dest = (path.parent / file_part).resolve() if file_part else path
            if not dest.exists():
                yield number, target, "no such file"
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                yield number, target, f"no heading #{anchor} in {dest.relative_to(ROOT)}"


def main(argv) -> int:
    files = [Path(a).resolve() for a in argv] or [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    problems = 0
    for path in files:
        for number, target, why in broken_links(path):
            print(f"{path.relative_to(ROOT)}:{number}: {target} ({why})")
            problems += 1
    checked = ", ".join(str(p.relative_to(ROOT)) for p in files)
    if problems:
        print(f"{problems} broken link(s)")
        return 1
    print(f"links: all relative links resolve in {len(files)} files ({checked})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
