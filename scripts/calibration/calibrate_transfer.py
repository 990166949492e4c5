#!/usr/bin/python3
"""The page of calibrate_transfer.sh: a `calibrate` fit on a validation split, scored elsewhere.

    calibrate_transfer.py DIR PAGE COMMAND

Reads DIR/compare_*/compare.json (each: `dempster` with the adaptive cap, and `dempster` with the
cap that `calibrate` fitted on the validation split) and writes PAGE: per dataset, protocol and
evidence, both caps, and the Brier score, ECE and AUROC of 1 - max p under each, with the
paired-bootstrap difference of the fitted cap's Brier score.
"""
import glob
import json
import os
import subprocess
import sys
from datetime import datetime, timezone

DEFAULT = "dempster"


def runs_by_section(directory):
    """(dataset, protocol, evidence) -> (adaptive run, calibrated run, bootstrap row)."""
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
            fitted = [v for v in runs if v != DEFAULT]
            if DEFAULT in runs and len(fitted) == 1:
                sections[key] = (runs[DEFAULT], runs[fitted[0]], boot.get(key + (fitted[0],)))
    return sections


def validation_split(run):
    if run["evidence_source"] == "file":
        return "another seed, same scene, sensor, network and scale (synthetic)"
    return "scans " + ", ".join(run["map_scans"]) + " (the mapped scans; queries: the others)"


def written_cap(run):
    """The cap of the calibration file: the fitted one, or "adaptive kept" (-1: the fit was not
    better than the adaptive cap beyond its interval on the validation split)."""
    if run["parameters"]["evidence_cap"] < 0:
        return "adaptive kept"
    return "%.2f" % run["tree"]["evidence_cap"]


def row(key, adaptive, fitted, boot):
    a, f = adaptive["map"], fitted["map"]
    diff = "–"
    if boot is not None:
        x = boot["brier_difference"]
        diff = "%+.4f [%+.4f, %+.4f]" % (x["estimate"], x["lower"], x["upper"])
    return "| %s | %s | %s | %s | %.2f (m %.2f) → %s | %.4f → %.4f | %s | %.3f → %.3f " \
        "| %.3f → %.3f |" % (
            key[0], key[1], key[2], validation_split(adaptive), adaptive["tree"]["evidence_cap"],
            adaptive["tree"]["mean_point_log_evidence"], written_cap(fitted),
            a["brier"], f["brier"], diff, a["ece"], f["ece"],
            a["error_detection"]["1-max_p"]["auroc"], f["error_detection"]["1-max_p"]["auroc"])


def main():
    directory, page, command = sys.argv[1:4]
    sections = runs_by_section(directory)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    commit = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    text = ["# A `calibrate` fit on a validation split, scored on other data", "",
            "Written by `%s` (commit %s, %s). A user with labelled scans of their own network "
            "runs `evidential_octomap calibrate` on them ([calibration.md](calibration.md"
            "#with-labelled-scans-of-your-own)); here the validation split is never the data "
            "scored. Generated datasets (**synthetic**): the sequences of the cross-dataset "
            "table ([calibration_tables.md](calibration_tables.md)), calibrated on a shorter "
            "sequence of the same kind with another seed. Bundled SemanticKITTI scans: "
            "calibrated on the held-out protocol's mapped scans, scored on its queries (the "
            "other scans). Cap: the adaptive cap with the map's m → the cap of the file "
            "`calibrate` wrote (it keeps the adaptive cap unless the fit has the lower Brier "
            "score on the validation split beyond the 95 %% bootstrap interval). Δ Brier: the "
            "file's cap's minus the adaptive cap's, paired bootstrap, 95 %% interval over 10 m "
            "blocks."
            % (command, commit, stamp), "",
            "| dataset | protocol | evidence | validation split | cap | Brier | Δ Brier | ECE | "
            "AUROC 1 − max p |", "|" + "---|" * 9]
    for key in sorted(sections):
        text.append(row(key, *sections[key]))
    with open(page, "w") as f:
        f.write("\n".join(text) + "\n")
    print("wrote " + page)


if __name__ == "__main__":
    main()
