#!/usr/bin/python3
"""The page of error_model.sh: the error model `calibrate` fits, scored on scans it never saw.

    error_model.py DIR PAGE COMMAND

Reads DIR/compare_*/compare.json (each section: dempster, dempster+calibration and the other
rules on the same queries) and DIR/scans_N/compare.json (offroad_all calibrated on N scans), and
writes PAGE: per section ECE, Brier and the AUROC with which each output ranks the map's wrong
labels, the targets of docs/calibration.md checked, and the curve over N.
"""
import glob
import json
import os
import subprocess
import sys
from datetime import datetime, timezone

from summarize import interval

CALIBRATED = "dempster+calibration"
OUTPUTS = ("u", "conflict", "1-max_p", "dissonance", "error_probability")
ECE_TARGET = 0.03


def sections(paths):
    """(dataset, protocol, evidence) -> ({variant: run}, {row: bootstrap})."""
    out = {}
    for path in paths:
        d = json.load(open(path))
        for r in d["runs"]:
            key = (r["dataset_label"], r["protocol"], r["evidence_source"])
            out.setdefault(key, ({}, {}))[0][r["variant_id"]] = r
        for b in d["bootstrap"]:
            key = (b["dataset_label"], b["protocol"], b["evidence"])
            if key in out:
                out[key][1][b["row"]] = b
    return out


def auroc(run, output):
    d = run["map"]["error_detection"].get(output)
    return d["auroc"] if d and d["auroc"] is not None else float("nan")


def best_other_output(runs):
    """The best AUROC of any output of any row but the calibrated error probability."""
    best = (float("-inf"), "")
    for variant, run in runs.items():
        for output in OUTPUTS:
            if variant == CALIBRATED and output == "error_probability":
                continue
            if variant != CALIBRATED and output == "error_probability" and \
                    auroc(run, output) == auroc(run, "1-max_p"):
                continue  # the same read-out as 1-max_p
            best = max(best, (auroc(run, output), variant + " " + output))
    return best


def best_other_brier(runs):
    return min((r["map"]["brier"], v) for v, r in runs.items() if v != CALIBRATED)


def mark(ok):
    return "yes" if ok else "**no**"


def section_row(key, runs, boot):
    default, cal = runs["dempster"], runs[CALIBRATED]
    brier, brier_rule = best_other_brier(runs)
    best_auroc, best_output = best_other_output(runs)
    cal_auroc = auroc(cal, "error_probability")
    sbki_u = auroc(runs["sbki"], "u") if "sbki" in runs else float("nan")
    delta = boot.get(CALIBRATED)
    return ("| %s | %s | %s | %.3f → %.3f | %.4f → %.4f | %s | %.4f (%s) | %.3f → **%.3f** | "
            "%.3f (%s) | %.3f | %.2f / %.2f | %s %s %s |" % (
                key[0], key[1], key[2], default["map"]["ece"], cal["map"]["ece"],
                default["map"]["brier"], cal["map"]["brier"],
                interval(delta["brier_difference"]) if delta else "–", brier, brier_rule,
                auroc(default, "1-max_p"), cal_auroc, best_auroc, best_output, sbki_u,
                100 * default["map"]["miou_all_queries"], 100 * cal["map"]["miou_all_queries"],
                mark(cal["map"]["ece"] <= ECE_TARGET), mark(cal["map"]["brier"] <= brier),
                mark(cal_auroc >= best_auroc)))


def targets_summary(all_sections):
    met = [0, 0, 0]
    keys = [k for k, v in all_sections.items() if CALIBRATED in v[0]]
    for k in keys:
        runs = all_sections[k][0]
        cal = runs[CALIBRATED]
        met[0] += cal["map"]["ece"] <= ECE_TARGET
        met[1] += cal["map"]["brier"] <= best_other_brier(runs)[0]
        met[2] += auroc(cal, "error_probability") >= best_other_output(runs)[0]
    return ("Targets met, of %d sections: calibrated ECE ≤ %s in %d; Brier ≤ every other rule's "
            "in %d; AUROC of the error probability ≥ every output of every rule in %d.\n" % (
                len(keys), ECE_TARGET, *met))


def section_table(all_sections):
    rows = [section_row(k, *v) for k, v in sorted(all_sections.items()) if CALIBRATED in v[0]]
    header = ("| dataset | protocol | evidence | ECE: dempster → calibrated | Brier: dempster → "
              "calibrated | Δ Brier [95 % CI] | best other Brier (rule) | AUROC: dempster "
              "1 − max p → calibrated error probability | best other output's AUROC | sbki u "
              "AUROC | mIoU all (dempster / calibrated) | ECE ≤ " + str(ECE_TARGET) + ", Brier ≤ "
              "every rule, AUROC ≥ every output |\n" + "|---" * 12 + "|\n")
    return header + "\n".join(rows) + "\n"


def uncalibrated_summary(all_sections):
    eces = [(v[0]["dempster"]["map"]["ece"], k) for k, v in all_sections.items()
            if "dempster" in v[0]]
    worst, key = max(eces)
    beaten = [k for k, v in all_sections.items() if "sbki" in v[0] and
              auroc(v[0]["dempster"], "1-max_p") < auroc(v[0]["sbki"], "u")]
    return ("Without a calibration file (the default read-out): the worst ECE over the %d "
            "sections is %.3f (%s, %s, %s); its 1 − max p ranks the wrong labels worse than "
            "sbki's u in %d of %d sections.\n" % (len(eces), worst, *key, len(beaten),
                                                  sum("sbki" in v[0] for v in all_sections.values())))


def curve_table(directory):
    rows = []
    for path in sorted(glob.glob(os.path.join(directory, "scans_*", "compare.json")),
                       key=lambda p: int(p.split("scans_")[-1].split("/")[0])):
        n = int(path.split("scans_")[-1].split("/")[0])
        for key, (runs, _) in sorted(sections([path]).items()):
            cal = runs[CALIBRATED]
            if not any(r[0] == 0 and r[1] == key[1] for r in rows):
                d = runs["dempster"]["map"]
                rows.append((0, key[1], d["ece"], d["brier"], auroc(runs["dempster"], "1-max_p")))
            rows.append((n, key[1], cal["map"]["ece"], cal["map"]["brier"],
                         auroc(cal, "error_probability")))
    rows.sort(key=lambda r: (r[1], r[0]))
    lines = ["| calibration scans | protocol | ECE | Brier | AUROC of the error probability |",
             "|---|---|---|---|---|"]
    for n, protocol, ece, brier, a in rows:
        lines.append("| %s | %s | %.3f | %.4f | %.3f |" % (
            "none (1 − max p)" if n == 0 else n, protocol, ece, brier, a))
    return "\n".join(lines) + "\n"


def main():
    directory, page, command = sys.argv[1:4]
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, cwd=os.path.dirname(os.path.abspath(__file__))).stdout.strip()
    date = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    all_sections = sections(sorted(glob.glob(os.path.join(directory, "compare_*", "compare.json"))))
    text = f"""# The map's error probability, fitted on a validation split and scored elsewhere

Written by `{command}` (commit {commit}, {date}). `evidential_octomap calibrate` fits the error
model ([calibration.md](../calibration.md#the-error-model)) on a validation split; `compare
--calibration FILE` maps the dataset with every rule and reads default dempster's map once more
with the file (**dempster+calibration**), so every row answers the same queries. Generated
datasets (**synthetic**, [data.md](../data.md)): calibrated on a sequence of the same family with
another seed, scored on the dataset's own sequence. wrong_regions, range_attenuated,
border_errors, scaled_x0.2 and scaled_x5 are network models the model's design was never tried
on; offroad_all is the family it was designed on (other seeds). Bundled SemanticKITTI scans:
calibrated on the held-out protocol's mapped scans (`--scans 5`), scored on its queries (the other
five); onehot evidence is **derived** from the hard predictions. The RELLIS-3D example is one scan
with another class table: there is no split to fit on, so it has no row. AUROC: how well an output
ranks the map's wrong labels above its right ones (0.5: chance); best other output: the highest
AUROC of u, 1 − max p, conflict and dissonance of every row (the calibrated row's too). Δ Brier:
calibrated minus dempster, paired bootstrap over 10 m blocks.

{section_table(all_sections)}
{targets_summary(all_sections)}
{uncalibrated_summary(all_sections)}
## How many labelled scans

offroad_all calibrated on the first N scans of its validation sequence, scored on its own
sequence (the same runs as above for N = 10):

{curve_table(directory)}"""
    with open(page, "w") as f:
        f.write(text)
    print("wrote", page)


if __name__ == "__main__":
    main()
