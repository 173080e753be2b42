#!/usr/bin/env python3
"""Checks that every relative link in the project's Markdown resolves, without the network.

Reads README.md, BENCHMARKS.md and every .md file under docs/ (and any other Markdown files
named on the command line). A link or image `[text](target)` whose target is not a URL must name
an existing file or folder, relative to the file that holds it; a `#fragment` (alone, or after a
Markdown file) must be the anchor of one of that file's headings, made the way GitHub makes
them. Links inside code (fenced blocks and `inline code`) are not links. Prints each broken
link as FILE:LINE: TARGET (why) and exits with 1 if there is any.
"""

import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")


def without_code(lines, blank_inline=True):
    """Yields (line number, text) with fenced blocks dropped and inline code blanked."""
    fence = None
    for number, line in enumerate(lines, 1):
        stripped = line.lstrip()
        marker = stripped[:3]
        if marker in ("```", "~~~"):
            if fence is None:
                fence = marker
            elif marker == fence:
                fence = None
            continue
        if fence is None:
            yield number, re.sub(r"`+[^`]*`+", "``", line) if blank_inline else line


def slug(title):
    """GitHub's anchor for a heading: lower case, markup and punctuation dropped, spaces to -."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", title)  # a link's text only
    text = text.replace("`", "").lower()
    text = "".join(c for c in text if c.isalnum() or c in " -_")
    return text.replace(" ", "-")


def anchors(path, cache={}):
    if path not in cache:
        seen, found = {}, set()
        for _, line in without_code(path.read_text(encoding="utf-8").splitlines(), False):
            m = HEADING.match(line)
            if not m:
                continue
            base = slug(m.group(2))
            n = seen.get(base, 0)
            seen[base] = n + 1
            found.add(base if n == 0 else f"{base}-{n}")
        cache[path] = found
    return cache[path]


def check(path):
    broken = []
    text = path.read_text(encoding="utf-8")
    for number, line in without_code(text.splitlines()):
        for m in LINK.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):  # http:, https:, mailto: …
                continue
            file_part, _, fragment = target.partition("#")
            dest = path if not file_part else (path.parent / file_part).resolve()
            where = f"{path.relative_to(ROOT)}:{number}: {target}"
            if not dest.exists():
                broken.append(f"{where} (no such file)")
            elif fragment and dest.suffix == ".md" and fragment not in anchors(dest):
                broken.append(f"{where} (no heading #{fragment} in {dest.relative_to(ROOT)})")
    return broken


def main():
    files = [ROOT / "README.md", ROOT / "BENCHMARKS.md"]
    files += sorted((ROOT / "docs").rglob("*.md"))
    files += [pathlib.Path(a).resolve() for a in sys.argv[1:]]
    files = [f for f in files if f.exists() and "book" not in f.relative_to(ROOT).parts[:2]]
    broken = [b for f in files for b in check(f)]
    for b in broken:
        print(b)
    print(f"links: {len(files)} Markdown files read, {len(broken)} broken link(s)")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())
