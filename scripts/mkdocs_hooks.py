"""mkdocs hook (mkdocs.yml `hooks:`): links from a docs page to a file outside docs/.

The pages are written to be read on the repository too, so they link to source files
(`../problems/x.json`, a plugin's README). The site holds only docs/, and mkdocs' strict mode
counts such a link as broken. This hook turns each into the repository path in code font
before mkdocs checks links; tests/docs/check_links.py checks that every such path exists. Links
inside docs/ are left to mkdocs, which fails the strict build on a broken one.
"""
import os
import re

LINK = re.compile(r"(!?)\[([^\]]*)\]\(([^)\s]+)\)")
FENCE = re.compile(r"^\s*```")


def _outside(target: str, page_dir: str, docs_dir: str, repo: str):
    """The repository-relative path of `target` when it leaves docs/, else None."""
    if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
        return None
    path = os.path.normpath(os.path.join(page_dir, target.split("#", 1)[0]))
    if path == docs_dir or path.startswith(docs_dir + os.sep):
        return None
    return os.path.relpath(path, repo)


def on_page_markdown(markdown, page, config, files):
    docs_dir = os.path.normpath(config["docs_dir"])
    repo = os.path.dirname(docs_dir)
    page_dir = os.path.dirname(page.file.abs_src_path)
    out, fenced = [], False
    for line in markdown.split("\n"):
        if FENCE.match(line):
            fenced = not fenced
        if not fenced:
            def replace(m):
                where = _outside(m.group(3), page_dir, docs_dir, repo)
                if where is None:
                    return m.group(0)
                label = m.group(2)
                if label.strip("`") == where or label.strip("`").endswith(where.split("/")[-1]) and "/" in label:
                    return f"`{where}`"
                return f"{label} (`{where}`)"
            line = LINK.sub(replace, line)
        out.append(line)
    return "\n".join(out)
