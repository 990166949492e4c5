#!/usr/bin/env python3
"""Draws docs/images/pipeline.png, the picture of how a map is made and read (README,
docs/how_it_works.md), stamped with the commit and date it was drawn at.

    /usr/bin/python3 scripts/docs/pipeline_figure.py [OUT.png]     (needs python3-matplotlib)
"""
import os
import subprocess
import sys
from datetime import datetime, timezone

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import FancyArrowPatch, FancyBboxPatch  # noqa: E402

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

# (x, y, title, detail, colour): one box per stage; x, y are the box centre.
STAGES = [
    (1.0, 3.0, "LiDAR scan",
     "x, y, z\n+ your network's\nlogits, probabilities,\nevidence or labels", "#dfe9f5"),
    (3.4, 3.0, "point evidence",
     "e >= 0 per class\nopinion b = e / S,\nvacuity u = C / S", "#dfe9f5"),
    (5.8, 3.9, "occupancy", "rays: OctoMap's\nlog-odds (free, hit)", "#e6f2df"),
    (5.8, 2.1, "kernel",
     "each point's evidence\nspread over nearby\nvoxels (sparse kernel)", "#e6f2df"),
    (8.2, 3.0, "voxel", "Dempster's rule in\nevidence space:\nlog-evidence L per class", "#fbeedb"),
    (10.6, 3.0, "read-out", "label = argmax b\nerror probability\nvacuity u, conflict", "#f6e0e0"),
    (13.0, 3.0, "outputs", ".ot / .bt files, views,\n~query, cost map,\nPython arrays", "#f6e0e0"),
]
ARROWS = [(0, 1), (1, 2), (1, 3), (2, 4), (3, 4), (4, 5), (5, 6)]
SIDE = [(1.0, 1.0, "TF: map <- sensor\nat the scan's stamp", 0), (10.6, 1.0,
        "calibration file (optional):\nerror model of your network", 5)]


def stamp():
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    return "scripts/docs/pipeline_figure.py, commit %s, %s" % (
        commit, datetime.now(timezone.utc).strftime("%Y-%m-%d"))


def box(ax, x, y, title, detail, colour, w=2.0, h=1.45):
    ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.04",
                                fc=colour, ec="#444444", lw=1.0))
    ax.text(x, y + h / 2 - 0.22, title, ha="center", va="center", fontsize=10, weight="bold")
    ax.text(x, y - 0.12, detail, ha="center", va="center", fontsize=7.5, linespacing=1.25)


def arrow(ax, a, b):
    ax.add_patch(FancyArrowPatch(a, b, arrowstyle="-|>", mutation_scale=12, lw=1.1,
                                 color="#333333", shrinkA=4, shrinkB=4))


def draw(path):
    fig, ax = plt.subplots(figsize=(13.5, 4.2))
    ax.set_xlim(-0.2, 14.2)
    ax.set_ylim(0.0, 4.9)
    ax.axis("off")
    for x, y, title, detail, colour in STAGES:
        box(ax, x, y, title, detail, colour)
    for i, j in ARROWS:
        (x0, y0), (x1, y1) = STAGES[i][:2], STAGES[j][:2]
        dx = 1.0 if x1 > x0 else 0.0
        start = (x0 + dx, y0) if dx else (x0, y0 - 0.72)
        end = (x1 - 1.0, y1) if dx else (x1, y1 + 0.72)
        arrow(ax, start, end)
    for x, y, text, target in SIDE:
        ax.text(x, y, text, ha="center", va="center", fontsize=7.5, style="italic",
                bbox=dict(boxstyle="round,pad=0.3", fc="white", ec="#999999", lw=0.8))
        tx, ty = STAGES[target][:2]
        arrow(ax, (x, y + 0.35), (tx, ty - 0.72))
    ax.text(14.2, 0.02, stamp(), ha="right", va="bottom", fontsize=6, color="#777777")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print("wrote %s" % os.path.relpath(path, ROOT))


if __name__ == "__main__":
    draw(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "images",
                                                             "pipeline.png"))
