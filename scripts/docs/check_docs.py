#!/usr/bin/env python3
"""The docs check (ctest `docs_check`): README and docs/ as a user reads them.

- every relative link of README, docs/*.md, docs/experiments/*.md and the other READMEs resolves,
  #anchors included;
- no user page (README, docs/*.md) tells project history (issue numbers, dated runs, commits,
  load averages, before/after) or quotes a measured figure outside a generated block;
- README has at most 150 lines; the user pages hold at most 20,000 words in all;
- the generated blocks (scripts/docs/figures.py) and the experiments index are current, every
  record has a stamp, and the planner example uses the cut-off its record recommends;
- docs/troubleshooting.md quotes only messages the sources hold, and every message of the map
  loader and the ROS 1 node.

    python3 scripts/docs/check_docs.py        # prints each problem; exit 1 when there is one
"""
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import doc_pages  # noqa: E402
import experiments_index  # noqa: E402
import figures  # noqa: E402
import messages  # noqa: E402

README_LINES = 150
USER_WORDS = 20000
# Other pages whose links are checked too.
OTHER_PAGES = ["CHANGELOG.md", "bench/README.md", "config/README.md", "data/README.md"]
# Pages a program writes whole (their numbers are the code's defaults, not measurements).
GENERATED_PAGES = {os.path.join("docs", "parameters.md")}

HISTORY = [
    (r"\bissue\s*#?\d+", "an issue number"),
    (r"(?<![\w(/])#\d+\b", "an issue number"),
    (r"\b20\d\d-\d\d-\d\d\b", "a dated run"),
    (r"\b\d\d:\d\d UTC\b", "a dated run"),
    (r"\bload average[^.\n]{0,20}\d", "a load-average log"),
    (r"\bcommits? [0-9a-f]{7,40}\b", "a commit"),
    (r"\bbefore/after\b|\b(?:before|after) (?:the )?commit\b", "a before/after of commits"),
]
FIGURE = [
    (r"\b\d+(?:\.\d+)? ?ms\b", "a measured time"),
    (r"\b\d+\.\d+ ?×(?! ?\d)", "a measured ratio"),
    (r"\bAUROC(?: of [\w −]+?)? (?:of )?0\.\d+", "a measured AUROC"),
    (r"\bmIoU (?:of )?\d+(?:\.\d+)? ?%", "a measured mIoU"),
]
_GENERATED = re.compile(
    r"<!-- generated: .*?<!-- end -->|<!-- ([\w-]+): ?begin -->.*?<!-- \1: ?end -->"
    r"|<!-- stamp:[\w-]+ -->\n[^\n]*", re.S)


def outside_generated(text):
    """The page with its generated blocks, code blocks and link targets blanked out."""
    text = _GENERATED.sub("", text)
    text = doc_pages.prose(text)
    return re.sub(r"\]\([^)]*\)", "]()", text)


def link_problems(root):
    out = []
    pages = doc_pages.user_pages(root) + doc_pages.record_pages(root) + [experiments_index.INDEX]
    pages += [p for p in OTHER_PAGES if os.path.exists(os.path.join(root, p))]
    for page in pages:
        for target in doc_pages.links(doc_pages.read(page, root)):
            why = doc_pages.broken_link(page, target, root)
            if why:
                out.append("%s: link %s: %s" % (page, target, why))
    return out


def pattern_problems(root, patterns, pages):
    out = []
    for page in pages:
        text = outside_generated(doc_pages.read(page, root))
        for n, line in enumerate(text.split("\n"), 1):
            for pattern, what in patterns:
                m = re.search(pattern, line, re.I)
                if m:
                    out.append("%s: %s (%r) outside a generated block" % (page, what, m.group(0)))
    return out


def size_problems(root):
    out = []
    lines = doc_pages.read("README.md", root).count("\n")
    if lines > README_LINES:
        out.append("README.md: %d lines, more than %d" % (lines, README_LINES))
    words = sum(doc_pages.words(doc_pages.read(p, root)) for p in doc_pages.user_pages(root))
    if words > USER_WORDS:
        out.append("user docs: %d words, more than %d" % (words, USER_WORDS))
    return out


def generated_problems(root):
    out = ["%s: %s (python3 scripts/docs/figures.py)" % p for p in figures.stale_pages(root)]
    current = doc_pages.read(experiments_index.INDEX, root)
    if current != experiments_index.index(root):
        out.append("%s is not current (python3 scripts/docs/experiments_index.py)"
                   % experiments_index.INDEX)
    return out + experiments_index.missing_stamps(root)


def cutoff_problems(root):
    """The planner example trusts a label below the cut-off its record recommends."""
    example = os.path.join(root, "examples", "planner_example.cpp")
    record = os.path.join(root, doc_pages.RECORDS, "cutoff.md")
    if not (os.path.exists(example) and os.path.exists(record)):
        return []
    used = re.search(r"kMaxErrorProbability = ([\d.]+)f", open(example).read())
    advised = re.search(r"Recommended cut-off: error probability < ([\d.]+)", open(record).read())
    if not used or not advised or float(used.group(1)) != float(advised.group(1)):
        return ["examples/planner_example.cpp: kMaxErrorProbability is not the cut-off of %s"
                % os.path.join(doc_pages.RECORDS, "cutoff.md")]
    return []


def message_problems(root):
    out = ["%s: `%s` occurs in no source" % (messages.PAGE, m)
           for m in messages.missing_in_sources(root)]
    out += ["%s: no row for %s's message %r" % (messages.PAGE, path, lit)
            for path, lit in messages.uncovered(root)]
    return out


def problems(root=doc_pages.ROOT):
    users = doc_pages.user_pages(root)
    measured = [p for p in users if p not in GENERATED_PAGES]
    return (link_problems(root) + pattern_problems(root, HISTORY, users)
            + pattern_problems(root, FIGURE, measured) + size_problems(root)
            + generated_problems(root) + cutoff_problems(root) + message_problems(root))


def main():
    found = problems()
    for p in found:
        print(p)
    print("docs check: %d problem(s)" % len(found))
    sys.exit(1 if found else 0)


if __name__ == "__main__":
    main()
