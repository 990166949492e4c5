"""What the docs checks read from Markdown: which pages are user guides and which are experiment
records, their relative links, their headings' anchors (as GitHub makes them) and their words."""
import os
import re

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
RECORDS = os.path.join("docs", "experiments")

_FENCE = re.compile(r"^(```|~~~).*?^\1", re.S | re.M)
_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$", re.M)


def user_pages(root=ROOT):
    """README.md and every docs/*.md: what a user reads (records live in docs/experiments/)."""
    docs = os.path.join(root, "docs")
    pages = ["README.md"] + sorted(os.path.join("docs", f) for f in os.listdir(docs)
                                   if f.endswith(".md"))
    return pages


def record_pages(root=ROOT):
    """Every experiment record: docs/experiments/*.md except the index."""
    folder = os.path.join(root, RECORDS)
    return sorted(os.path.join(RECORDS, f) for f in os.listdir(folder)
                  if f.endswith(".md") and f != "README.md")


def read(path, root=ROOT):
    with open(os.path.join(root, path), encoding="utf-8") as f:
        return f.read()


def prose(text):
    """The text without fenced code blocks and HTML comments (code and markers are not prose)."""
    return re.sub(r"<!--.*?-->", "", _FENCE.sub("", text), flags=re.S)


def words(text):
    return len(prose(text).split())


def links(text):
    """Every relative link target of the page (no scheme, no mail), code blocks excluded."""
    out = []
    for target in _LINK.findall(prose(text)):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
            continue
        out.append(target)
    return out


def slug(heading):
    """The anchor GitHub gives a heading: lower case, no punctuation, spaces to hyphens."""
    text = re.sub(r"`|\*\*|\*|<[^>]+>", "", heading)
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text, flags=re.U)
    return text.replace(" ", "-")


def anchors(text):
    """The anchors of every heading of the page, duplicates numbered as GitHub numbers them."""
    seen = {}
    out = set()
    for _, heading in _HEADING.findall(_FENCE.sub("", text)):
        base = slug(heading)
        n = seen.get(base, 0)
        out.add(base if n == 0 else "%s-%d" % (base, n))
        seen[base] = n + 1
    out.update(re.findall(r"<a (?:name|id)=\"([^\"]+)\"", text))
    return out


def broken_link(page, target, root=ROOT):
    """Why the relative link `target` of `page` does not resolve, or None when it does."""
    path, _, anchor = target.partition("#")
    here = os.path.dirname(os.path.join(root, page))
    full = os.path.normpath(os.path.join(here, path)) if path else os.path.join(root, page)
    if not os.path.exists(full):
        return "no file %s" % os.path.relpath(full, root)
    if anchor and full.endswith(".md"):
        with open(full, encoding="utf-8") as f:
            if anchor not in anchors(f.read()):
                return "no heading #%s in %s" % (anchor, os.path.relpath(full, root))
    return None
