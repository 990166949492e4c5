#!/usr/bin/python3
"""Candidate settings of the default, scored on every dataset of the cross-dataset table.

    across_datasets.py OUT PAGE TITLE COMMAND

Reads OUT/compare_*/compare.json (written by across_datasets.sh) and writes PAGE: per dataset,
protocol and evidence, each variant's Brier score, ECE and read-out cap, the AUROC of 1 - max p
for the voxel's errors, mIoU over all queries, the paired-bootstrap difference to `dempster` (the
default) and the classes with >= 1,000 GT queries below the input's IoU (reconstruction); then
the leave-one-dataset-out choice: for each dataset, the variant with the lowest mean Brier
relative to the best variant of each section, over the *other* datasets' sections.
"""
import glob
import json
import os
import subprocess
import sys
from collections import defaultdict
from datetime import datetime, timezone

DEFAULT = "dempster"


def sections(out):
    """(dataset, protocol, evidence) -> {variant: run}, and the bootstrap rows by the same key."""
    runs, boot = defaultdict(dict), {}
    for path in sorted(glob.glob(os.path.join(out, "compare_*", "compare.json"))):
        d = json.load(open(path))
        for r in d["runs"]:
            runs[(r["dataset_label"], r["protocol"], r["evidence_source"])][r["variant_id"]] = r
        for b in d["bootstrap"]:
            boot[(b["dataset_label"], b["protocol"], b["evidence"], b["row"])] = b
    return runs, boot


def thin_classes_below_input(run):
    if run["protocol"] != "reconstruction":
        return "–"
    below = ["%s %.1f < %.1f" % (c["name"], 100 * c["map_iou_all_queries"], 100 * c["input_iou"])
             for c in run["per_class"]
             if c["gt_queries"] >= 1000 and c["map_iou_all_queries"] is not None
             and c["input_iou"] and c["map_iou_all_queries"] < c["input_iou"]]
    return ", ".join(below) or "none"


def interval(b, key, scale, digits):
    if b is None:
        return "–"
    x = b[key]
    f = "%+." + str(digits) + "f"
    return (f + " [" + f + ", " + f + "]") % (scale * x["estimate"], scale * x["lower"],
                                               scale * x["upper"])


def readout_cap(run):
    """dempster's read-out cap and, in brackets, the map's m that the adaptive cap follows."""
    tree = run["tree"]
    if tree.get("evidence_cap") is None:
        return "–"
    return "%.2f (%.2f)" % (tree["evidence_cap"], tree["mean_point_log_evidence"])


def section_table(runs, boot, variants):
    lines = ["| dataset | protocol | evidence | variant | Brier | Δ Brier vs dempster | ECE | "
             "cap (m) | AUROC 1 − max p | mIoU all % | Δ mIoU vs dempster (points) | classes "
             "below input IoU | kernel CPU s |", "|" + "---|" * 13]
    for key in sorted(runs):
        for v in variants:
            r = runs[key].get(v)
            if r is None:
                continue
            m = r["map"]
            b = None if v == DEFAULT else boot.get(key + (v,))
            lines.append("| %s | %s | %s | `%s` | %.4f | %s | %.3f | %s | %.3f | %.2f | %s | %s "
                         "| %.1f |" % (
                key[0], key[1], key[2], v, m["brier"], interval(b, "brier_difference", 1, 4),
                m["ece"], readout_cap(r), m["error_detection"]["1-max_p"]["auroc"],
                100 * m["miou_all_queries"], interval(b, "miou_all_difference", 100, 2),
                thin_classes_below_input(r), r["timing"]["cpu_ms_kernel_total"] / 1000))
    return lines


def relative_brier(runs, variants):
    """(dataset, section key) -> {variant: Brier / best Brier of the section}."""
    rel = {}
    for key, by_variant in runs.items():
        if not all(v in by_variant for v in variants):
            continue
        best = min(by_variant[v]["map"]["brier"] for v in variants)
        rel[key] = {v: by_variant[v]["map"]["brier"] / best for v in variants}
    return rel


def leave_one_out_table(runs, variants):
    rel = relative_brier(runs, variants)
    datasets = sorted({k[0] for k in rel})
    mean = lambda keys, v: sum(rel[k][v] for k in keys) / len(keys)
    lines = ["| dataset held out | chosen on the others (mean Brier / best) | its Brier / best "
             "there | best there |", "|---|---|---|---|"]
    for held in datasets:
        others = [k for k in rel if k[0] != held]
        mine = [k for k in rel if k[0] == held]
        choice = min(variants, key=lambda v: mean(others, v))
        best_here = min(variants, key=lambda v: mean(mine, v))
        lines.append("| %s | `%s` (%s) | %.4f | `%s` (%.4f) |" % (
            held, choice, ", ".join("%s %.4f" % (v, mean(others, v)) for v in variants),
            mean(mine, choice), best_here, mean(mine, best_here)))
    everything = list(rel)
    lines += ["", "Mean over every section: " + ", ".join(
        "`%s` %.4f" % (v, mean(everything, v)) for v in variants) + "."]
    return lines


def main():
    out, page, title, command = sys.argv[1:5]
    runs, boot = sections(out)
    variants = []
    for by_variant in runs.values():
        for v in by_variant:
            if v not in variants:
                variants.append(v)
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
    commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    text = ["# " + title, "",
            "Written by `%s` (commit %s, %s). The datasets and queries of the cross-dataset "
            "table ([calibration_tables.md](calibration_tables.md)): the bundled SemanticKITTI "
            "scans (learned and derived one-hot evidence), the RELLIS-3D scan (synthetic "
            "predictions) and four **synthetic** generated sequences; every variant of a "
            "section answers the same queries. Δ: paired bootstrap against `dempster` (the "
            "default), 95 %% interval over 10 m blocks. cap (m): the read-out cap of a dempster "
            "map and the mean point log-evidence m of its evidence "
            "([calibration.md](../calibration.md)). Classes below the input: classes with "
            "≥ 1,000 GT queries whose map IoU is below the per-point input's (reconstruction)."
            % (command, commit, stamp), ""]
    text += section_table(runs, boot, variants)
    text += ["", "## Leave one dataset out", "",
             "For each dataset, the variant with the lowest mean relative Brier score (Brier / "
             "the best variant's in the same section) over the other datasets' sections, and "
             "what it scores on the dataset left out.", ""]
    text += leave_one_out_table(runs, variants)
    with open(page, "w") as f:
        f.write("\n".join(text) + "\n")
    print("wrote " + page)


if __name__ == "__main__":
    main()
