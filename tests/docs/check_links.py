#!/usr/bin/env python3
"""Checks the documentation's cross-references against the tree (ctest Docs.LinksAndNamedConstantsResolve).

1. Every relative Markdown link in the README, docs/ and each README, KERNELS.md and
   BLOCK_BOUNDS.md (the kernels' design notes) under framework/, plugins/, python/, examples/,
   tests/ names a file or directory that exists (anchors are not followed).
2. docs/limits.md names the constants that hold each limit: each `kName` it quotes is defined
   (`kName =`) somewhere under framework/ or plugins/, and each XmlShapeLimits field it quotes
   is a member of that struct. A limit renamed or removed in the code fails here until its page
   follows.

Standard library only. Exit status 0 when everything resolves, 1 otherwise (each problem listed).
"""
import argparse
import re
import sys
from pathlib import Path

LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```")


def markdown_files(root: Path) -> list:
    files = [root / "README.md"] + sorted((root / "docs").rglob("*.md"))
    for top in ("framework", "plugins", "python", "examples", "tests", "share"):
        for name in ("README.md", "KERNELS.md", "BLOCK_BOUNDS.md"):  # the kernels' design notes too
            files += sorted((root / top).rglob(name))
    return [f for f in files if f.is_file()]


def links_of(text: str) -> list:
    """(line number, target) of every link outside fenced code blocks."""
    out, fenced = [], False
    for number, line in enumerate(text.splitlines(), 1):
        if FENCE.match(line.strip()):
            fenced = not fenced
            continue
        if not fenced:
            out += [(number, m.group(1)) for m in LINK.finditer(line)]
    return out


def broken_links(root: Path) -> list:
    problems = []
    for f in markdown_files(root):
        for number, target in links_of(f.read_text(encoding="utf-8")):
            if re.match(r"^[a-z]+:", target) or target.startswith("#"):
                continue  # a URL or an anchor in the same page
            path = target.split("#", 1)[0]
            if not (f.parent / path).exists():
                problems.append(f"{f.relative_to(root)}:{number}: link to {target}: no such file")
    return problems


def unknown_constants(root: Path) -> list:
    page = root / "docs" / "limits.md"
    text = page.read_text(encoding="utf-8")
    sources = [p.read_text(encoding="utf-8", errors="replace")
               for top in ("framework", "plugins") for p in (root / top).rglob("*") if p.suffix in (".cpp", ".hpp")]
    problems = []
    for name in sorted(set(re.findall(r"`(k[A-Z][A-Za-z0-9]+)`", text))):
        if not any(re.search(rf"\b{name}\s*=", s) for s in sources):
            problems.append(f"docs/limits.md: constant {name} is not defined under framework/ or plugins/")
    shape = (root / "plugins" / "mechanisms" / "serial_chain" / "xml_shape.hpp").read_text(encoding="utf-8")
    for field in sorted(set(re.findall(r"`XmlShapeLimits::([a-z_]+)`", text))):
        if not re.search(rf"\b{field}\s*=", shape):
            problems.append(f"docs/limits.md: XmlShapeLimits has no member {field}")
    return problems


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default=str(Path(__file__).resolve().parents[2]))
    root = Path(ap.parse_args().root)
    problems = broken_links(root) + unknown_constants(root)
    for p in problems:
        print(p)
    checked = len(markdown_files(root))
    print(f"check_links: {checked} Markdown files, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
