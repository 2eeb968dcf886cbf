#!/usr/bin/env python3
"""Checks the relative links of Loam's documentation (standard library only).

For README.md, docs/**/*.md (the tutorials in docs/tutorial/ too) and laws/README.md (or the
files given as arguments): every markdown link `[text](target)`, image `![alt](target)` and
HTML `src="target"` whose target is a relative path must name a file or directory that
exists, and every `#anchor` into a markdown file (or into the file itself) must match one of
its headings under GitHub's rules (lowercase; characters other than letters, digits, `_`, `-`
and spaces removed; spaces to `-`; a repeated heading gets `-1`, `-2`, ...). Links inside fenced code blocks and inline
code are ignored, as GitHub does not render them. Prints each broken link with its file and
line and exits 1 if there is any; otherwise prints a one-line summary.

    python3 scripts/check_links.py            # from anywhere in the repository
"""
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
SRC = re.compile(r"""\bsrc=["']([^"']+)["']""")
HEADING = re.compile(r"^ {0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^ {0,3}(```|~~~)")


def strip_code(line):
    """The line with inline code spans blanked (links in them are not links)."""
    return re.sub(r"(`+)(?:(?!\1).)+\1", lambda m: " " * len(m.group(0)), line)


def lines_outside_fences(text):
    """(line number, line) for every line outside fenced code blocks."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        m = FENCE.match(line)
        if m:
            if fence is None:
                fence = m.group(1)
                continue
            if m.group(1) == fence:
                fence = None
                continue
        if fence is None:
            yield number, line


def slug(heading):
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML tags
    text = text.lower()
    text = re.sub(r"[^\w\- ]", "", text)  # keeps letters, digits, _, -, spaces
    return text.replace(" ", "-")


_anchors = {}


def anchors(path):
    """The anchors of a markdown file's headings (cached)."""
    if path not in _anchors:
        seen = {}
        found = set()
        for _, line in lines_outside_fences(path.read_text(encoding="utf-8")):
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            count = seen.get(base, 0)
            found.add(base if count == 0 else f"{base}-{count}")
            seen[base] = count + 1
        _anchors[path] = found
    return _anchors[path]


def check(path):
    """The broken links of one markdown file, as messages; and the number of links checked."""
    problems = []
    checked = 0
    text = path.read_text(encoding="utf-8")
    for number, line in lines_outside_fences(text):
        plain = strip_code(line)
        targets = [m.group(1) for m in LINK.finditer(plain)] + [m.group(1) for m in SRC.finditer(plain)]
        for target in targets:
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target):  # http:, https:, mailto:, ...
                continue
            checked += 1
            where = f"{path.relative_to(ROOT)}:{number}: {target}"
            file_part, _, anchor = target.partition("#")
            dest = path if file_part == "" else (path.parent / file_part).resolve()
            if not dest.exists():
                problems.append(f"{where}: no such file")
                continue
            if anchor and dest.is_file() and dest.suffix == ".md" and anchor not in anchors(dest):
                problems.append(f"{where}: no heading with the anchor #{anchor} in {dest.relative_to(ROOT)}")
    return problems, checked


def main(args):
    files = [Path(a).resolve() for a in args] or (
        [ROOT / "README.md"] + sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "laws" / "README.md"]
    )
    problems = []
    checked = 0
    for f in files:
        p, c = check(f)
        problems += p
        checked += c
    for p in problems:
        print(p)
    if problems:
        print(f"check_links: {len(problems)} broken of {checked} relative links in {len(files)} files")
        return 1
    print(f"check_links: {checked} relative links in {len(files)} files, all resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
