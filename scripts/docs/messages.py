"""The error messages of the sources and of docs/troubleshooting.md, for the docs check.

A message of the sources is the first string literal of a throw, a ROS_FATAL/ROS_ERROR/ROS_WARN
or a Python raise; its text is that literal's constant part (format directives cut out). The
page lists messages in its tables: the first backticked span of a row's first cell, written as
the user sees it, of which every piece between `...` must occur in one source literal.
"""
import os
import re

import doc_pages

PAGE = os.path.join("docs", "troubleshooting.md")

# Every message of these files must have a row in the page: what loadMap and the ROS 1 node say.
MUST_COVER = [
    "src/core/io.cpp", "src/core/ot_format.cpp", "src/ros/ros_params.cpp",
    "src/ros/MappingServer.cpp", "src/ros/visualization.cpp", "src/ros/projected_map.cpp",
    "src/ros/evidential_mapping_node.cpp",
]
# Where a row's message may come from.
SOURCES = ["src", "python/evidential_octomap", "scripts", "include", "CMakeLists.txt", "cmake"]

_CALL = re.compile(
    r"(?:throw\s+(?:std::)?\w+\s*\(|FormatError\s*\(|ROS_(?:FATAL|ERROR|WARN)(?:_THROTTLE|_ONCE)?"
    r"\s*\((?:\s*[\d.]+\s*,)?|raise\s+\w+\s*\(\s*f?)\s*(?:std::string\s*\(\s*)?"
    r"(?:[\w.()]+\s*\+\s*)?\"((?:[^\"\\]|\\.)*)\"")


def literals(path, root=doc_pages.ROOT):
    """The constant texts of the messages raised or logged in one source file."""
    with open(os.path.join(root, path), encoding="utf-8") as f:
        text = f.read()
    out = []
    for raw in _CALL.findall(text):
        pieces = [p.strip(" :;,(") for p in re.split(r"%[-+ #0-9.]*[a-zA-Z]|\{[^}]*\}|\\n", raw)]
        piece = max(pieces, key=len)
        if len(piece) >= 6:
            out.append(piece)
    return out


def source_files(root=doc_pages.ROOT):
    for top in SOURCES:
        full = os.path.join(root, top)
        if os.path.isfile(full):
            yield top
            continue
        for folder, _, files in os.walk(full):
            for name in files:
                if name.endswith((".cpp", ".h", ".py", ".sh", ".cmake", ".txt")):
                    yield os.path.relpath(os.path.join(folder, name), root)


# Messages of other programs (CMake, Python) that the page explains; not in our sources.
EXTERNAL = ["Could not find a package configuration file provided by", "No module named catkin_pkg"]


def page_messages(root=doc_pages.ROOT):
    """The messages of the page's table rows: every backticked span of a row's first cell."""
    out = []
    for line in doc_pages.read(PAGE, root).split("\n"):
        if line.startswith("| `"):
            out += re.findall(r"`([^`]+)`", line.split("|")[1])
    return out


def pieces(message):
    """The parts of a page message that must occur verbatim in a source: split at `...`."""
    return [p.strip() for p in message.split("...") if len(p.strip()) >= 4]


def missing_in_sources(root=doc_pages.ROOT):
    """Page messages some piece of which no source file contains."""
    corpus = []
    for path in source_files(root):
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
            corpus.append(f.read())
    text = "\n".join(corpus)
    return [m for m in page_messages(root)
            if m not in EXTERNAL and not all(p in text for p in pieces(m))]


def uncovered(root=doc_pages.ROOT):
    """(file, message) of the must-cover messages that no row of the page names."""
    listed = [p for m in page_messages(root) for p in pieces(m)]
    out = []
    for path in MUST_COVER:
        for lit in literals(path, root):
            if not any(p in lit or lit in p for p in listed):
                out.append((path, lit))
    return out
