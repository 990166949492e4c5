#!/usr/bin/python3
"""The page of calibrate_transfer.sh: a `calibrate` fit on a validation split, scored elsewhere.

    calibrate_transfer.py DIR PAGE COMMAND

Reads DIR/compare_*/compare.json (each: `dempster` with the adaptive cap, with the cap of the
file `calibrate` wrote on the validation split and, when that file kept the adaptive cap (-1),
with the fit it did not keep) and writes PAGE: per dataset, protocol and evidence, the caps, the
Brier score and ECE under each and the paired-bootstrap difference of the Brier scores.
"""
import glob
import json
import os
import subprocess
import sys
from datetime import datetime, timezone

from summarize import interval

DEFAULT = "dempster"


def runs_by_section(directory):
    """(dataset, protocol, evidence) -> (adaptive run, file's run, fit's run, bootstrap rows).
    The file's run reads with the cap `calibrate` wrote; the fit's is the fitted cap, the same
    run unless the file kept the adaptive cap (-1)."""
    sections = {}
    for path in sorted(glob.glob(os.path.join(directory, "compare_*", "compare.json"))):
        d = json.load(open(path))
        boot = {(b["dataset_label"], b["protocol"], b["evidence"], b["row"]): b
                for b in d["bootstrap"]}
        by_key = {}
        for r in d["runs"]:
            by_key.setdefault((r["dataset_label"], r["protocol"], r["evidence_source"]), {})[
                r["variant_id"]] = r
        for key, runs in by_key.items():
            others = [r for v, r in runs.items() if v != DEFAULT]
            kept = [r for r in others if r["parameters"]["evidence_cap"] < 0]
            fitted = [r for r in others if r["parameters"]["evidence_cap"] >= 0]
            if DEFAULT not in runs or len(fitted) != 1:
                continue
            written = (kept or fitted)[0]
            sections[key] = (runs[DEFAULT], written, fitted[0],
                             {r["variant_id"]: boot.get(key + (r["variant_id"],))
                              for r in others})
    return sections


def validation_split(run):
    if run["evidence_source"] == "file":
        return "another seed, same scene, sensor, network and scale (synthetic)"
    return "scans " + ", ".join(run["map_scans"]) + " (the mapped scans; queries: the others)"


def written_cap(run):
    """The cap of the calibration file: the fitted one, or "adaptive" (-1: the fit was not
    better than the adaptive cap beyond its interval on the validation split)."""
    if run["parameters"]["evidence_cap"] < 0:
        return "adaptive"
    return "%.2f" % run["tree"]["evidence_cap"]


def brier_difference(boot):
    if boot is None:
        return "±0"  # the file's cap is the adaptive one: the same map
    return interval(boot["brier_difference"])


def row(key, adaptive, written, fit, boot):
    a, w, f = adaptive["map"], written["map"], fit["map"]
    unkept = "–" if fit is written else "%.2f: %.4f (%s), ECE %.3f" % (
        fit["tree"]["evidence_cap"], f["brier"], brier_difference(boot[fit["variant_id"]]),
        f["ece"])
    return ("| %s | %s | %s | %s | %.2f (m %.2f) → %s | %.4f → %.4f | %s | %.3f → %.3f "
            "| %s |") % (
        key[0], key[1], key[2], validation_split(adaptive), adaptive["tree"]["evidence_cap"],
        adaptive["tree"]["mean_point_log_evidence"], written_cap(written), a["brier"], w["brier"],
        brier_difference(boot.get(written["variant_id"])), a["ece"], w["ece"], unkept)


def main():
    directory, page, command = sys.argv[1:4]
    sections = runs_by_section(directory)
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
    commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    text = ["# A `calibrate` fit on a validation split, scored on other data", "",
            "Written by `%s` (commit %s, %s). A user with labelled scans of their own network "
            "runs `evidential_octomap calibrate` on them ([calibration.md](../calibration.md"
            "#with-labelled-scans-of-your-own)); here the validation split is never the data "
            "scored. Generated datasets (**synthetic**): the sequences of the cross-dataset "
            "table ([calibration_tables.md](calibration_tables.md)), calibrated on a shorter "
            "sequence of the same kind with another seed. Bundled SemanticKITTI scans: "
            "calibrated on the held-out protocol's mapped scans, scored on its queries (the "
            "other scans). Cap: the adaptive cap with the map's m → the cap of the file "
            "`calibrate` wrote: the fit when its Brier score on the validation split is lower "
            "beyond the 95 %% bootstrap interval, else the adaptive cap. Δ Brier: the file's "
            "cap's minus the adaptive cap's, paired bootstrap, 95 %% interval over 10 m blocks. "
            "Fit not kept: the fitted cap that the file did not keep (what `--keep-fit` "
            "writes), its Brier score (Δ against the adaptive cap) and ECE."
            % (command, commit, stamp), "",
            "| dataset | protocol | evidence | validation split | cap | Brier | Δ Brier | ECE | "
            "fit not kept |", "|" + "---|" * 9]
    for key in sorted(sections):
        text.append(row(key, *sections[key]))
    with open(page, "w") as f:
        f.write("\n".join(text) + "\n")
    print("wrote " + page)


if __name__ == "__main__":
    main()
