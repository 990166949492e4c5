#!/usr/bin/python3
"""The cross-dataset tables of docs/experiments/calibration_tables.md and its reliability diagrams, from the
compare.json files that docs/experiments/drivers/calibration/cross_dataset.sh writes.

    /usr/bin/python3 docs/experiments/drivers/calibration/summarize.py out/cross_dataset docs/experiments/calibration_tables.md \
        docs/images/reliability_cross_dataset.png

Targets checked for the default rule (dempster) on every dataset, protocol and evidence source:
ECE <= 0.05; no rule with a Brier score lower beyond its paired-bootstrap interval; AUROC of the
default uncertainty (1 - max p) for the voxel's label being wrong >= 0.80 and >= the input's
per-point AUROC of its u (where the input has a per-point u); mIoU over all queries within the
interval of the best rule; in reconstruction (the map queried at the points it was built from,
so the input's IoU is comparable) no class with >= 1000 GT queries below the input's IoU.
"""
import datetime
import glob
import json
import os
import subprocess
import sys

RULES = ("dempster", "sbki", "ebs", "reference_compat")
# The map's default uncertainty, the one its uncertainty view shows (~uncertainty_view): the
# probability that a voxel's label is wrong, 1 - max_c p_c. The vacuity u is reported beside it.
DEFAULT_UNCERTAINTY = "1-max_p"
ECE_MAX, AUROC_MIN, THIN_MIN_QUERIES = 0.05, 0.80, 1000


def load_sections(root):
    """{(dataset label, protocol, evidence): {"runs": {variant: run}, "bootstrap": {row: b}}}"""
    sections = {}
    for path in sorted(glob.glob(os.path.join(root, "compare_*", "compare.json"))):
        with open(path) as f:
            compare = json.load(f)
        for run in compare["runs"]:
            key = (run["dataset_label"], run["protocol"], run["evidence_source"])
            sections.setdefault(key, {"runs": {}, "bootstrap": {}})["runs"][run["variant_id"]] = run
        for b in compare["bootstrap"]:
            key = (b["dataset_label"], b["protocol"], b["evidence"])
            if key in sections:
                sections[key]["bootstrap"][b["row"]] = b
    return sections


def synthetic(label):
    return "SYNTHETIC" in label.upper() or not label.startswith(("semantickitti", "RELLIS"))


def dataset_name(label):
    if label.startswith("RELLIS"):
        return "RELLIS-3D scan 000104 (synthetic predictions)"
    if label.startswith("semantickitti"):
        return "SemanticKITTI 08, bundled 10 scans"
    return label + " (synthetic)"


def interval(d, scale=1.0, fmt="%+.4f"):
    return (fmt + " [" + fmt + ", " + fmt + "]") % (d["estimate"] * scale, d["lower"] * scale,
                                                    d["upper"] * scale)


def input_auroc(run):
    u = run["input"].get("error_detection", {}).get("u")
    # A one-hot or hard-label input has one u for every point: no per-point signal (AUROC 0.5).
    if not u or run["evidence_source"] in ("onehot",) or abs(u["auroc"] - 0.5) < 0.03:
        return None
    return u["auroc"]


def thin_classes(run):
    return [c for c in run["per_class"]
            if c["gt_queries"] >= THIN_MIN_QUERIES and c["map_iou_all_queries"] < c["input_iou"]]


def majority_note(run, c):
    """The voxel majority of the input's own labels (no kernel) for a class, when it too is below
    the input: then the voxel size, not the kernel, bounds that class."""
    m = c.get("voxel_majority_iou")
    if m is None or m >= c["input_iou"]:
        return ""
    return " (voxel majority %.1f)" % (100 * m)


def targets(section):
    """One row of the targets table for the dempster map of a section, and whether all are met."""
    runs, boot = section["runs"], section["bootstrap"]
    d = runs["dempster"]["map"]
    others = [r for r in RULES[1:] if r in boot]
    ece_ok = d["ece"] <= ECE_MAX
    better_brier = [r for r in others if boot[r]["brier_difference"]["upper"] < 0]
    best_other = min(others, key=lambda r: boot[r]["brier_difference"]["estimate"])
    brier_cell = "%.4f; best other %s %s" % (d["brier"], best_other,
                                           interval(boot[best_other]["brier_difference"]))
    au, au_in = d["error_detection"][DEFAULT_UNCERTAINTY]["auroc"], input_auroc(runs["dempster"])
    au_u = d["error_detection"]["u"]["auroc"]
    auroc_ok = au >= AUROC_MIN and (au_in is None or au >= au_in)
    better_miou = [r for r in others if boot[r]["miou_all_difference"]["lower"] > 0]
    best_miou = max(others, key=lambda r: boot[r]["miou_all_difference"]["estimate"])
    miou_cell = "%.1f; best other %s %s" % (100 * d["miou_all_queries"], best_miou,
                                           interval(boot[best_miou]["miou_all_difference"], 100,
                                                    "%+.2f"))
    reconstruction = runs["dempster"]["protocol"] == "reconstruction"
    thin = thin_classes(runs["dempster"]) if reconstruction else None
    thin_cell = "–" if thin is None else (", ".join(
        "%s %.1f < %.1f%s" % (c["name"], 100 * c["map_iou_all_queries"], 100 * c["input_iou"],
                              majority_note(runs["dempster"], c))
        for c in thin) or "none")
    checks = [ece_ok, not better_brier, auroc_ok, not better_miou, not thin]
    mark = lambda ok: "" if ok else " **✗**"
    return ("| %.3f%s | %s%s | %.3f%s | %s%s | %s%s |" % (
        d["ece"], mark(ece_ok), brier_cell, mark(not better_brier),
        au, " (u %.3f%s)" % (au_u, "; input %.3f" % au_in if au_in else "") + mark(auroc_ok),
        miou_cell, mark(not better_miou), thin_cell, mark(not thin)), all(checks))


def top_classes(counts, names, skip, n=3):
    """The n largest counts other than class `skip`, as "name count" (the last column: no label)."""
    named = [(k, names.get(i, "no label")) for i, k in enumerate(counts) if i != skip and k]
    return ", ".join("%s %s" % (name, "{:,}".format(k))
                     for k, name in sorted(named, reverse=True)[:n]) or "none"


def where_thin_classes_go(sections, w):
    """For each class below the input's IoU: how the input and the map label its GT queries and
    how many other queries each labels with it (the confusion matrices of compare.json)."""
    lines = []
    for key in sorted(sections, key=order):
        run = sections[key]["runs"]["dempster"]
        if run["protocol"] != "reconstruction" or "confusion" not in run:
            continue
        names = {c["class"]: c["name"] for c in run["per_class"]}
        for c in thin_classes(run):
            i = c["class"]
            m, x = run["confusion"]["map"], run["confusion"]["input"]
            others = lambda matrix: sum(row[i] for g, row in enumerate(matrix) if g != i)
            lines.append(
                "- %s, %s, %s (%s GT queries): labelled %s by the input %s times (and %s other "
                "queries), by the map %s times (and %s others); the map gives the rest to %s "
                "(the input: %s).\n" % (
                    dataset_name(key[0]), key[2], c["name"], "{:,}".format(c["gt_queries"]),
                    c["name"], "{:,}".format(x[i][i]), "{:,}".format(others(x)),
                    "{:,}".format(m[i][i]), "{:,}".format(others(m)),
                    top_classes(m[i], names, i), top_classes(x[i], names, i)))
    if lines:
        w("\nWhere the queries of each class below the input's IoU go (reconstruction, "
          "`dempster`; from the confusion matrices of compare.json):\n\n" + "".join(lines))


def write_targets(sections, w):
    w("| dataset | protocol | evidence | ECE | Brier (Δ best other rule) | AUROC 1 − max p | mIoU all % "
      "(Δ best other rule, points) | classes below input IoU | all met |\n")
    w("|---|---|---|---|---|---|---|---|---|\n")
    met = 0
    for key in sorted(sections, key=order):
        row, ok = targets(sections[key])
        met += ok
        w("| %s | %s | %s %s %s |\n" % (dataset_name(key[0]), key[1], key[2], row,
                                        "yes" if ok else "no"))
    w("\n%d of %d sections meet every target.\n" % (met, len(sections)))
    where_thin_classes_go(sections, w)


def replace_block(path, text):
    begin, end = "<!-- cross-dataset: begin -->", "<!-- cross-dataset: end -->"
    with open(path) as f:
        page = f.read()
    if begin not in page or end not in page:
        sys.exit("%s: no %s ... %s block" % (path, begin, end))
    head, rest = page.split(begin, 1)
    with open(path, "w") as f:
        f.write(head + begin + "\n" + text + end + rest.split(end, 1)[1])


def run_commit(root):
    """The commit the compare runs were made at (cross_dataset.sh records it), else HEAD."""
    try:
        with open(os.path.join(root, "commit.txt")) as f:
            return f.read().strip()
    except OSError:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True).stdout.strip()


def write_tables(sections, out, commit):
    w = out.write
    w("# Cross-dataset tables\n\nProduced by `docs/experiments/drivers/calibration/cross_dataset.sh` and "
      "`docs/experiments/drivers/calibration/summarize.py` (runs at commit %s, tables %s). Generated datasets are **synthetic** "
      "(`evidential_octomap generate`, [data.md](../data.md)); none of them, nor the bundled or "
      "RELLIS-3D data, was used to choose the adaptive cap's constants "
      "([calibration.md](../calibration.md)). Every row of a section uses the same queries. "
      "Intervals: paired spatial-block bootstrap against dempster (95 %%, 1000 replicates).\n\n"
      % (commit, datetime.date.today()))
    w("## Targets of the default (`dempster`, adaptive cap)\n\n"
      "✗ marks a target missed: ECE > %.2f; a rule with lower Brier beyond the interval; AUROC "
      "of the default uncertainty (1 − max p, the probability that the label is wrong; the "
      "vacuity u beside it) < %.2f or below the input's per-point AUROC of its u; a rule with "
      "higher mIoU beyond the "
      "interval; a class with ≥ %d GT queries below the input's IoU (reconstruction only).\n\n"
      % (ECE_MAX, AUROC_MIN, THIN_MIN_QUERIES))
    write_targets(sections, w)
    w("\n")
    w("## Every rule\n\n| dataset | protocol | evidence | row | mIoU all % | Brier | Δ Brier "
      "vs dempster | ECE | AUROC 1 − max p | AUROC u |\n|---|---|---|---|---|---|---|---|---|---|\n")
    for key in sorted(sections, key=order):
        runs, boot = sections[key]["runs"], sections[key]["bootstrap"]
        first = runs["dempster"]["input"]
        au_in = input_auroc(runs["dempster"])
        w("| %s | %s | %s | input, per point | %.1f | %.4f | | %.4f | | %s |\n" % (
            dataset_name(key[0]), key[1], key[2], 100 * first["miou_all_queries"],
            first["brier"], first["ece"], "%.3f" % au_in if au_in else "–"))
        for rule in RULES:
            if rule not in runs:
                continue
            m = runs[rule]["map"]
            delta = interval(boot[rule]["brier_difference"]) if rule in boot else "–"
            w("| | | | %s | %.1f | %.4f | %s | %.4f | %.3f | %.3f |\n" % (
                rule, 100 * m["miou_all_queries"], m["brier"], delta, m["ece"],
                m["error_detection"][DEFAULT_UNCERTAINTY]["auroc"],
                m["error_detection"]["u"]["auroc"]))


def order(key):
    label, protocol, evidence = key
    return (not label.startswith("semantickitti"), not label.startswith("RELLIS"), label,
            protocol != "reconstruction", evidence)


def plot_reliability(sections, png, commit):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = [k for k in sorted(sections, key=order) if k[1] == "reconstruction"]
    cols = 4
    rows = (len(keys) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.2 * rows), squeeze=False)
    for ax, key in zip(axes.flat, keys):
        runs = sections[key]["runs"]
        ax.plot([0, 1], [0, 1], color="0.7", lw=1)
        for what, run, style in (("input", runs["dempster"]["input"], "k:"),
                                 ("dempster", runs["dempster"]["map"], "C0-o"),
                                 ("sbki", runs.get("sbki", {}).get("map"), "C1-s")):
            if not run:
                continue
            bins = [b for b in run["reliability"] if b["count"] > 0]
            ax.plot([b["mean_confidence"] for b in bins], [b["accuracy"] for b in bins], style,
                    ms=3, lw=1.2, label="%s (ECE %.3f)" % (what, run["ece"]))
        ax.set_title("%s\n%s evidence" % (dataset_name(key[0])[:38], key[2]), fontsize=8)
        ax.set_xlim(0, 1), ax.set_ylim(0, 1)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=6, loc="upper left")
    for ax in axes.flat[len(keys):]:
        ax.axis("off")
    fig.supxlabel("confidence (max projected probability)", fontsize=9)
    fig.supylabel("accuracy", fontsize=9)
    fig.suptitle("Reliability per dataset, reconstruction protocol (generated datasets are "
                 "SYNTHETIC); commit %s, %s" % (commit, datetime.date.today()), fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main():
    if len(sys.argv) not in (4, 5):
        sys.exit(__doc__)
    sections = load_sections(sys.argv[1])
    if not sections:
        sys.exit("%s: no compare_*/compare.json" % sys.argv[1])
    commit = run_commit(sys.argv[1])
    with open(sys.argv[2], "w") as out:
        write_tables(sections, out, commit)
        out.write("\n![Reliability diagrams](../images/%s)\n" % os.path.basename(sys.argv[3]))
    plot_reliability(sections, sys.argv[3], commit)
    if len(sys.argv) == 5:
        lines = []
        write_targets(sections, lines.append)
        figure = os.path.relpath(sys.argv[3], os.path.dirname(os.path.abspath(sys.argv[4])))
        replace_block(sys.argv[4], "Runs at commit %s, %s (docs/experiments/drivers/calibration/cross_dataset.sh)."
                      "\n\n%s\n![Reliability diagrams](%s)\n"
                      % (commit, datetime.date.today(), "".join(lines), figure))


if __name__ == "__main__":
    main()
