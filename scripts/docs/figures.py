#!/usr/bin/env python3
"""The figures the user guides quote from the experiment records, generated from the records.

A guide holds a block
    <!-- generated: figures KEY -->
    ...
    <!-- end -->
whose body this script writes from the record named in FIGURES[KEY], so a figure in a guide is
never copied by hand and changes when its record is regenerated.

    python3 scripts/docs/figures.py           # rewrite every block
    python3 scripts/docs/figures.py --check   # exit 1 when a block is not what its record gives
"""
import json
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import doc_pages  # noqa: E402
import experiments_index  # noqa: E402

BLOCK = re.compile(r"(<!-- generated: figures (\w+) -->\n)(.*?)(<!-- end -->)", re.S)


class MissingFigure(Exception):
    pass


def find(pattern, text, what):
    """The groups of `pattern` in `text` (whitespace-normalised); a record that lost the figure
    is an error that names it, so the guide cannot silently keep an old number."""
    m = re.search(pattern, " ".join(text.split()))
    if not m:
        raise MissingFigure("%s: no %r" % (what, pattern))
    return m.groups()


def record(name):
    path = os.path.join(doc_pages.RECORDS, name)
    text = doc_pages.read(path)
    _, _, commit, date = experiments_index.stamp(text)
    return text, "[%s](%s)" % (name, "experiments/" + name), commit, date


def row(text, first_cell, what):
    """The cells of the table row whose first cell is `first_cell`."""
    for line in text.split("\n"):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if cells and cells[0].replace("*", "") == first_cell:
            return [c.replace("*", "") for c in cells]
    raise MissingFigure("%s: no row %r" % (what, first_cell))


def live_rate():
    text, link, _, _ = record("live_profile.md")
    rate, received, dropped, seconds, median, date, commit = find(
        r"\*\*([\d.]+) clouds inserted a second\*\* of ([\d.]+) received, (none|[\d,]+) dropped "
        r"in (\d+) s[^*]*median insert \*\*([\d.]+) ms\*\*", text, "live_profile.md") + find(
        r"(20\d\d-\d\d-\d\d) [\d:]+ UTC, commit ([0-9a-f]{7})[^)]*\): \*\*[\d.]+ clouds inserted",
        text, "live_profile.md")
    return ("The node with the live profile, fed the bundled scans at 10 Hz on 2 cores (50 m), "
            "inserted **%s clouds a second** of %s received, %s dropped in %s s (median insert "
            "%s ms; %s, commit %s, %s)." % (rate, received, dropped, seconds, median, link, commit,
                                            date))


def ros2_rate():
    text, link, _, _ = record("ros2.md")
    commit, date, received, inserted = find(  # the row's own run
        r"commit ([0-9a-f]{7}), (20\d\d-\d\d-\d\d)[^|]*?(\d+) of \d+ clouds received, "
        r"\*\*(\d+) inserted\*\*", text, "ros2.md")
    return ("At 10 Hz with the live profile the ROS 2 node inserted %s of %s clouds and "
            "counted the rest as dropped (%s, commit %s, %s)." % (inserted, received, link,
                                                                  commit, date))


def local_map_memory():
    text, link, commit, date = record("local_map.md")
    local = row(text, "semantic insert, LocalMap radius 60 m (tiles on disk)", "local_map.md")
    whole = row(text, "semantic insert, whole map in memory", "local_map.md")
    return ("On a synthetic 1 km sequence the resident memory at the end was %s with a 60 m "
            "local map against %s with the whole map in memory; the global map merged from the "
            "tiles equals the whole map (%s, commit %s, %s)." % (local[4], whole[4], link, commit,
                                                                 date))


def error_model():
    text, link, commit, date = record("results_error_model.md")
    sections, ranked = find(r"Targets met, of (\d+) sections: .*? AUROC of the error probability "
                            r"≥ every output of every rule in (\d+)\.", text,
                            "results_error_model.md")
    kitti = row(text, "semantickitti_08_first10", "results_error_model.md")
    return ("The calibrated error probability ranked the map's wrong labels better than every "
            "output of every rule in %s of %s datasets and protocols; on the bundled scans "
            "(learned evidence, held-out) its AUROC was %s (1 − max p → calibrated) (%s, "
            "commit %s, %s)." % (ranked, sections, kitti[7], link, commit, date))


def learned_heldout():
    text, link, commit, date = record("learned_evidence.md")
    learned = row(text, "learned (cross-fitted)", "learned_evidence.md")
    hard = row(text, "network's hard predictions (p = one-hot)", "learned_evidence.md")
    return ("Per point, held out: accuracy %s %% against the network's %s %%, mIoU %s %% "
            "against %s %%, and an AUROC of u for wrong labels of %s (%s, commit %s, %s)." % (
                learned[1], hard[1], learned[2], hard[2], learned[6], link, commit, date))


def speed():
    _, link, commit, date = record("benchmarks.md")
    path = os.path.join(doc_pages.ROOT, "bench", "results", "benchmarks.json")
    s = json.load(open(path))["summary"]
    key = "cpu_ratio_%s_vs_plain_r50_steady"
    if key % "live" not in s or key % "exact" not in s:
        raise MissingFigure("bench/results/benchmarks.json: no %s or %s" % (key % "live",
                                                                            key % "exact"))
    return ("In a map that already knows the area, an insert costs %.2f× plain OctoMap's CPU "
            "with the library defaults and %.2f× with the live launch's settings (50 m, "
            "2 threads; %s, commit %s, %s)." % (s[key % "exact"], s[key % "live"], link,
                                                 commit, date))


def cutoff():
    text, link, commit, date = record("cutoff.md")
    cut, share, rate = find(r"Recommended cut-off: error probability < ([\d.]+): it keeps "
                            r"([\d.]+ %) of the labelled queries, of which ([\d.]+ %) are wrong",
                            text, "cutoff.md")
    return ("Trust a label when its error probability is below **%s**: on the bundled scans "
            "(held-out) that keeps %s of the labelled queries, of which %s are wrong (%s, "
            "commit %s, %s)." % (cut, share, rate, link, commit, date))


def merge_equality():
    text, link, commit, date = record("python.md")
    exact = row(text, "10 x 1, in order (sequential)", "python.md")
    plain = row(text, "10 x 1, plain (sequential)", "python.md")
    return ("Ten one-scan chunks of the bundled scans merged in order: %s query labels differ "
            "from the sequential map (beliefs to %s); merged without the unplaced evidence, %s "
            "do (%s, commit %s, %s)." % (exact[1], exact[2], plain[1], link, commit, date))


def data_presets():
    text, link, commit, date = record("data.md")
    good, poor = row(text, "good", "data.md"), row(text, "poor", "data.md")
    return ("Per point on a forest sequence, the `good` preset's network is right %s of the time "
            "(AUROC of u for its errors %s), the `poor` one's %s (%s) (%s, commit %s, %s)." % (
                good[2], good[3], poor[2], poor[3], link, commit, date))


def ghosts():
    text, link, commit, date = record("moving_objects.md")
    on, off = row(text, "defaults", "moving_objects.md"), row(text, "defaults, clearing off",
                                                              "moving_objects.md")
    live = row(text, "live profile", "moving_objects.md")
    gen, gen_link, gen_commit, gen_date = record("clearing_observations.md")
    families = [r for r in (line.strip("|").split("|") for line in gen.split("\n"))
                if len(r) == 10 and r[0].strip() in ("farm", "forest", "grassland", "rocky")]

    def values(settings, column):
        found = [float(r[column].strip(" %")) for r in families if r[1].strip() == settings]
        if not found:
            raise MissingFigure("clearing_observations.md: no %s rows" % settings)
        return found

    return ("Ten scans after a person or a car passed a static LiDAR (synthetic street), at most "
            "%s of the volume it freed still answered its class with the defaults (%s of it "
            "free in plain OctoMap too), and %s of the road layer under its path, against %s "
            "and %s with the clearing off; %s (%s) and %s with the live profile "
            "(%s, commit %s, %s). On generated off-road sequences, people and vehicles moving "
            "throughout, at most %.1f %% (%.2f %% free in plain OctoMap) of what they left ten "
            "scans before and rays cleared answered their class with the defaults, %.1f %% "
            "(%.2f %%) live, against %.0f %% or more with the clearing off, the static accuracy "
            "unchanged (%s, commit %s, %s)." % (
                on[1], on[2], on[5], off[1], off[5], live[1], live[2], live[5], link, commit,
                date, max(values("defaults", 3)), max(values("defaults", 4)),
                max(values("live profile", 3)), max(values("live profile", 4)),
                min(values("defaults, clearing off", 3)),
                gen_link, gen_commit, gen_date))


def clearing_cost():
    text, link, commit, date = record("clearing_static_cost.md")
    cells = {}
    for line in text.split("\n"):
        r = [c.strip() for c in line.strip().strip("|").split("|")]
        default = len(r) == 6 and r[0] == "movable classes after 1 (the default)"
        if default and (r[1], r[2]) not in cells:
            cells[(r[1], r[2])] = r[3]
    if len(cells) < 4:
        raise MissingFigure("clearing_static_cost.md: no default rows")
    return ("On the bundled street, its moving cars' points left out, the default clearing "
            "changes mIoU by %s (one-hot) and %s (learned) points held out, %s and %s "
            "reconstructed (95 %% intervals; %s, commit %s, %s)." % (
                cells[("held-out", "onehot")], cells[("held-out", "learned")],
                cells[("reconstruction", "onehot")], cells[("reconstruction", "learned")], link,
                commit, date))


def clearing_speed():
    text, link, commit, date = record("live_round.md")
    steady = {}
    for line in text.split("\n"):
        r = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(r) == 7 and r[0] == "after":
            steady.setdefault(r[1], []).append(r[3])  # the revisit's, then the off-road's
    try:
        on, off = steady["exact (library defaults)"], steady["exact, movable clearing off"]
        live_on, live_off = steady["live launch settings"], steady["live, movable clearing off"]
    except KeyError:
        raise MissingFigure("live_round.md: no after rows with and without the clearing")
    return ("Steady-state CPU with / without it, as a share of plain OctoMap's: exact %s× / "
            "%s× (bundled scans revisited), %s× / %s× (generated off-road); live %s× / %s×, "
            "%s× / %s× (%s, commit %s, %s)." % (
                on[0], off[0], on[1], off[1], live_on[0], live_off[0], live_on[1], live_off[1],
                link, commit, date))


def live_quality():
    text, link, commit, date = record("live_quality.md")
    miou, brier = [], []
    for line in text.split("\n"):
        r = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(r) == 7 and r[0] in ("held-out", "reconstruction"):
            miou.append(float(r[3].split()[0]))
            brier.append(float(r[5].split()[0]))
    if len(miou) < 4:
        raise MissingFigure("live_quality.md: no protocol rows")
    return ("Against the exact map on the bundled scans: %+.2f to %+.2f mIoU points, %+.4f to "
            "%+.4f Brier, mostly from the kernel length (%s, commit %s, %s)." % (max(miou), min(miou), min(brier), max(brier), link,
                                            commit, date))


FIGURES = {f.__name__: f for f in (live_rate, live_quality, ros2_rate, local_map_memory,
                                   error_model, learned_heldout, speed, cutoff, merge_equality,
                                   data_presets, ghosts, clearing_cost, clearing_speed)}


def render(text, page):
    """The page with every block's body regenerated, its links relative to the page."""
    records = os.path.relpath(os.path.join("docs", "experiments"), os.path.dirname(page) or ".")

    def body(m):
        key = m.group(2)
        if key not in FIGURES:
            raise MissingFigure("no figure %r (scripts/docs/figures.py FIGURES)" % key)
        figure = FIGURES[key]().replace("](experiments/", "](%s/" % records)
        return m.group(1) + figure + "\n" + m.group(4)
    return BLOCK.sub(body, text)


def stale_pages(root=doc_pages.ROOT):
    """(page, reason) of every user page whose blocks differ from what the records give."""
    out = []
    for page in doc_pages.user_pages(root):
        text = doc_pages.read(page, root)
        try:
            if render(text, page) != text:
                out.append((page, "a figures block is not current"))
        except MissingFigure as e:
            out.append((page, str(e)))
    return out


def main():
    if sys.argv[1:] == ["--check"]:
        stale = stale_pages()
        for page, why in stale:
            print("%s: %s" % (page, why))
        sys.exit(1 if stale else 0)
    for page in doc_pages.user_pages():
        text = doc_pages.read(page)
        new = render(text, page)
        if new != text:
            with open(os.path.join(doc_pages.ROOT, page), "w", encoding="utf-8") as f:
                f.write(new)
            print("wrote %s" % page)


if __name__ == "__main__":
    main()
