#!/usr/bin/python3
"""Tables and the per-scan plot of evidential_sequence_bench's CSV files (markdown on stdout).

    bench/sequence_report.py --revisit revisit.csv [--long long.csv --long-label TEXT]
        [--rss plain=rss_plain.csv --rss exact=rss_exact.csv] --png docs/images/x.png

Ratios are sums of CPU (or wall) time over the steps of a phase, of one method over plain
OctoMap's, all from the one interleaved run in the file.
"""
import argparse
import csv
import statistics
from collections import defaultdict

METHODS = [("plain", "plain OcTree::insertPointCloud"),
           ("exact", "semantic insert, exact (library defaults)"),
           ("live", "live launch settings (fast free space, length_scale 0.2, ds_multiplier 2, "
                    "evidence_floor 0.01, semantic_occupied_only)"),
           ("live_volume", "live launch settings without semantic_occupied_only"),
           ("occupied_only", "semantic insert, exact, semantic_occupied_only (evidence in occupied "
                             "voxels only: a different map)")]
STEADY = (10, 30)  # steps 10-29 of the revisit: the map already knows the area


def read(path):
    """{method: [row dict per step, in step order]}"""
    rows = defaultdict(list)
    with open(path) as f:
        for r in csv.DictReader(f):
            rows[r["method"]].append({k: (v if k == "method" else float(v)) for k, v in r.items()})
    for v in rows.values():
        v.sort(key=lambda r: r["step"])
    return rows


def total(rows, field, lo, hi):
    return sum(r[field] for r in rows[lo:hi])


def med(rows, field, lo, hi):
    return statistics.median(r[field] for r in rows[lo:hi])


def semantic_pass(r):
    return r["cpu_ms_kernel"] + r["cpu_ms_update"]


def phase_rows(data, phases):
    out = ["| method | phase | median CPU ms/scan | median wall ms/scan | CPU ratio to plain | "
           "wall ratio to plain | rays / kernel / update CPU ms (medians) |",
           "|---|---|---|---|---|---|---|"]
    plain = data["plain"]
    for key, label in METHODS:
        if key not in data:
            continue
        rows = data[key]
        for name, lo, hi in phases:
            hi = min(hi, len(plain), len(rows))
            if lo >= hi:
                continue  # a run stopped before this phase
            cpu = total(rows, "cpu_ms", lo, hi) / total(plain, "cpu_ms", lo, hi)
            wall = total(rows, "wall_ms", lo, hi) / total(plain, "wall_ms", lo, hi)
            parts = "–" if key == "plain" else " / ".join(
                f"{med(rows, f, lo, hi):.1f}" for f in ("cpu_ms_rays", "cpu_ms_kernel", "cpu_ms_update"))
            out.append(f"| {label} | {name} (steps {lo}–{hi - 1}) | {med(rows, 'cpu_ms', lo, hi):.1f} | "
                       f"{med(rows, 'wall_ms', lo, hi):.1f} | {cpu:.3f} | {wall:.3f} | {parts} |")
    return out


def flatness_rows(long):
    out = ["| method | part | median CPU ms, first 10 scans | median CPU ms, scans 100–199 | "
           "median CPU ms, last 100 scans | last 100 / scans 100–199 (target ≤ 1.2) |",
           "|---|---|---|---|---|---|"]
    for key, label in METHODS:
        if key not in long:
            continue
        rows = long[key]
        n = len(rows)
        parts = [("whole insert", lambda r: r["cpu_ms"])]
        if key != "plain":
            parts += [("occupancy (ray casting)", lambda r: r["cpu_ms_rays"]),
                      ("semantic pass (kernel + tree update)", semantic_pass)]
        for part, value in parts:
            first = statistics.median(value(r) for r in rows[:10])
            if n < 300:  # the two windows would overlap or be empty
                out.append(f"| {label} ({n} scans) | {part} | {first:.1f} | – | – | – |")
                continue
            a = statistics.median(value(r) for r in rows[100:200])
            b = statistics.median(value(r) for r in rows[n - 100:])
            out.append(f"| {label} ({n} scans) | {part} | {first:.1f} | {a:.1f} | {b:.1f} | "
                       f"{b / a:.3f} |")
    return out


def rss_rows(long):
    plain = long.get("plain")
    out = ["| method | scans | peak RSS after the first 100 scans | peak RSS at the end | largest "
           "ratio of its peak RSS to plain's after the same scan |", "|---|---|---|---|---|"]
    for key, label in METHODS:
        if key not in long:
            continue
        rows = long[key]
        worst = "–"
        if plain and key != "plain":
            n = min(len(rows), len(plain))
            worst = (f"{max(rows[i]['peak_rss_mb'] / plain[i]['peak_rss_mb'] for i in range(n)):.3f}"
                     f" (over the first {n} scans, the ones both runs reached)")
        out.append(f"| {label} | {len(rows)} | {rows[min(99, len(rows) - 1)]['peak_rss_mb']:.1f} MB | "
                   f"{rows[-1]['peak_rss_mb']:.1f} MB | {worst} |")
    return out


def plot(revisit, long, long_label, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    panels = [(revisit, "bundled scans forth and back (revisit, 50 m, one interleaved run)")]
    if long:
        panels.append((long, long_label + " (each method alone)"))
    fig, axes = plt.subplots(1, len(panels), figsize=(6.5 * len(panels), 4), squeeze=False)
    for ax, (data, title) in zip(axes[0], panels):
        for key, label in METHODS:
            if key not in data:
                continue
            ax.plot([r["step"] for r in data[key]], [r["cpu_ms"] for r in data[key]],
                    label=key + (" (library defaults)" if key == "exact" else
                                 " (launch settings)" if key == "live" else " OctoMap"), lw=1)
        ax.set_xlabel("scan index (insert order)")
        ax.set_ylabel("CPU ms per insert (2 threads)")
        ax.set_title(title, fontsize=9)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
    axes[0][0].axvspan(*STEADY, color="grey", alpha=0.15, label="steady state (steps 10–29)")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--revisit", required=True)
    p.add_argument("--long", action="append", default=[], help="method=csv of an --only run")
    p.add_argument("--long-label", default="long generated sequence (SYNTHETIC)")
    p.add_argument("--fewer-rows", help="a revisit run with occupied_only beside plain and exact")
    p.add_argument("--png", required=True)
    p.add_argument("--png-link", required=True, help="the PNG's path as the markdown links it")
    a = p.parse_args()
    revisit = read(a.revisit)
    long = {k: read(v)[k] for k, v in (s.split("=", 1) for s in a.long)}
    lines = ["### Revisit: the bundled scans forth and back at their real poses (50 m, 2 threads)",
             "", f"{len(revisit['plain'])} steps: scans 0..9, 8..0, 1..9, ... . First pass = a map "
             "still filling; steady state = steps 10–29, a map that already knows the area.", ""]
    lines += phase_rows(revisit, [("first pass", 0, 10), ("steady state", *STEADY),
                                  ("whole run", 0, len(revisit["plain"]))])
    if a.fewer_rows:
        fewer = read(a.fewer_rows)
        steps = len(fewer["plain"])
        lines += ["", "### Fewer kernel rows: semantic evidence in occupied voxels only",
                  "", "What the kernel costs when only occupied voxels get rows "
                  "(`semantic_occupied_only`, an existing option that changes the map): another "
                  f"interleaved run of {steps} revisit steps.", ""]
        lines += phase_rows(fewer, [("first pass", 0, 10), ("steady state", 10, min(30, steps))])
    if long:
        lines += ["", f"### {a.long_label}", "", "Each scan inserted once, each method alone in its "
                  "process (so no ratios here: the revisit gives them).", ""]
        lines += flatness_rows(long)
        lines += ["", "Peak RSS (getrusage) of each of those processes after every scan:", ""]
        lines += rss_rows(long)
    plot(revisit, long, a.long_label, a.png)
    lines += ["", f"![CPU per insert against scan index]({a.png_link})", ""]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
