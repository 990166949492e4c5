#!/usr/bin/python3
"""Tables and the RSS plot of scripts/bench_local_map.sh's output directory (markdown on stdout).

    bench/local_map_report.py OUT [--docs]

--docs writes the section into docs/experiments/local_map.md between its markers and the plot into
docs/images/local_map_memory.png.
"""
import argparse
import csv
import json
import os

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
METHODS = [("plain", "plain OcTree::insertPointCloud"),
           ("exact", "semantic insert, whole map in memory"),
           ("local", "semantic insert, LocalMap radius 60 m (tiles on disk)")]
MARKERS = ("<!-- local-map-memory: begin -->", "<!-- local-map-memory: end -->")


def read_csv(path):
    with open(path) as f:
        return [{k: (v if k == "method" else float(v)) for k, v in r.items()}
                for r in csv.DictReader(f)]


def memory_rows(runs):
    plain = runs["plain"]
    out = ["| method | scans | peak RSS after scan 100 | after scan 200 | at the end | "
           "last 100 scans / scans 100–199 (target ≤ 1.1) | largest ratio to plain's peak RSS "
           "after the same scan |", "|---|---|---|---|---|---|---|"]
    for key, label in METHODS:
        rows = runs[key]
        n = len(rows)
        peak = [r["peak_rss_mb"] for r in rows]
        flat = f"{max(peak[n - 100:]) / max(peak[100:200]):.3f}" if n >= 300 else "–"
        ratio = "–"
        if key != "plain":
            m = min(n, len(plain))
            worst = max(range(m), key=lambda i: peak[i] / plain[i]["peak_rss_mb"])
            ratio = (f"{peak[worst] / plain[worst]['peak_rss_mb']:.3f} (after scan {worst + 1}; "
                     f"at the end {peak[m - 1] / plain[m - 1]['peak_rss_mb']:.3f})")
        after = [f"{peak[min(i, n - 1)]:.0f} MB" for i in (99, 199, n - 1)]
        out.append(f"| {label} | {n} | {' | '.join(after)} | {flat} | {ratio} |")
    return out


def equality_rows(io_local):
    c = io_local["compare"]
    return ["| leaves compared | leaves missing in either map | labels differ | occupied/free "
            "state differs | largest payload difference (relative) |", "|---|---|---|---|---|",
            f"| {c['leaves']:,} | {c['leaves_missing_in_either']} | {c['labels_differ']} | "
            f"{c['occupied_state_differs']} | {c['largest_relative_payload_difference']:.2g} |"]


def io_rows(maps):
    """maps: [(scans, io json)] in order of size."""
    out = ["| scans | leaves (semantic) | .ot / .bt | `loadMap` wall / CPU | plain "
           "`OcTree::readBinary` of its .bt, wall / CPU | load ratio wall / CPU | `saveMap` wall / "
           "CPU | RSS once loaded | `query` / plain `search` per point |", "|---" * 9 + "|"]
    for scans, io in maps:
        load, plain, save = io["load_ms"], io["plain_read_binary_ms"], io["save_ms"]
        leaves = f"{io['leaves'] / 1e6:.1f} M ({io['semantic_leaves'] / 1e6:.1f} M)"
        out.append(f"| {scans} | {leaves} | {io['ot_mb']:,.0f} / {io['bt_mb']:,.0f} MB | "
                   f"{load[0]:,.0f} / {load[1]:,.0f} ms | "
                   f"{plain[0]:,.0f} / {plain[1]:,.0f} ms | "
                   f"{load[0] / plain[0]:.1f}× / {load[1] / plain[1]:.1f}× | "
                   f"{save[0]:,.0f} / {save[1]:,.0f} ms | {io['rss_after_load_mb']:,.0f} MB | "
                   f"{io['query_us']:.2f} / {io['plain_search_us']:.2f} µs |")
    return out


def plot(runs, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7.5, 4))
    for key, label in METHODS:
        rows = runs[key]
        ax.plot([r["step"] + 1 for r in rows], [r["rss_mb"] / 1e3 for r in rows], lw=1, label=label)
    ax.set_xlabel("scans inserted")
    ax.set_ylabel("RSS of the process [GB]")
    ax.set_title("long SYNTHETIC forest sequence, 0.2 m, max range 50 m", fontsize=9)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("out", help="the directory scripts/bench_local_map.sh wrote")
    p.add_argument("--docs", action="store_true")
    a = p.parse_args()
    runs = {key: read_csv(os.path.join(a.out, key + ".csv")) for key, _ in METHODS}
    sizes = sorted(int(f[len("io_exact_"):-len(".json")]) for f in os.listdir(a.out)
                   if f.startswith("io_exact_") and f.endswith(".json"))
    maps = [(n, json.load(open(os.path.join(a.out, f"io_exact_{n}.json")))) for n in sizes]
    maps.append((len(runs["exact"]), json.load(open(os.path.join(a.out, "io_exact.json")))))
    io_local = json.load(open(os.path.join(a.out, "io_local.json")))
    meta = open(os.path.join(a.out, "meta.txt")).read().rstrip().replace(
        os.path.abspath(a.out), "OUT")  # the record names the directory as the script's usage
    png = (os.path.join(REPO, "docs/images/local_map_memory.png") if a.docs
           else os.path.join(a.out, "local_map_memory.png"))
    plot(runs, png)
    lines = ["*Generated by `bench/local_map_report.py` from `scripts/bench_local_map.sh` "
             "(SYNTHETIC sequence, derived one-hot evidence × 20, 2 threads). Its record:*", "",
             "```", meta, "```", "", "RSS (getrusage) of each process after every scan:", ""]
    lines += memory_rows(runs)
    lines += ["", "![RSS against scans inserted](../images/local_map_memory.png)", "",
              "The local map's global map (tiles merged with the resident map, "
              "`LocalMap::globalMap`) against the whole map, leaf by leaf "
              "(`evidential_map_io_bench --same-as`):", ""]
    lines += equality_rows(io_local)
    lines += ["", "Save, load and query of the whole map after a third, two thirds and all of the "
              "sequence (`evidential_map_io_bench`: medians of 3 loads and saves; 10^6 queries at "
              "random points in random leaves of the map):", ""]
    lines += io_rows(maps)
    text = "\n".join(lines)
    print(text)
    if a.docs:
        path = os.path.join(REPO, "docs/experiments/local_map.md")
        doc = open(path).read()
        head, rest = doc.split(MARKERS[0])
        tail = rest.split(MARKERS[1])[1]
        with open(path, "w") as f:
            f.write(head + MARKERS[0] + "\n" + text + "\n" + MARKERS[1] + tail)


if __name__ == "__main__":
    main()
