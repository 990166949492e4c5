#!/usr/bin/python3
"""Writes the README's results table from the demo's metrics.json (bash scripts/demo.sh), between
the markers <!-- results:begin --> and <!-- results:end -->, stamped with the commit and date.

    /usr/bin/python3 scripts/docs/readme_results.py out/demo/metrics.json README.md
"""
import json
import subprocess
import sys
from datetime import datetime, timezone

BEGIN, END = "<!-- results:begin -->", "<!-- results:end -->"


def row(name, m):
    detection = m.get("error_detection", {}).get("error_probability")
    auroc = detection["auroc"] if detection else float("nan")
    return "| %s | %.1f | %.1f | %.4f | %.4f | %.3f |" % (
        name, 100 * m["miou_all_queries"], 100 * m["acc_all_queries"], m["brier"], m["ece"], auroc)


def table(metrics, commit, date):
    rule = metrics["parameters"]["rule"]
    lines = [
        "| %s GT-labelled points of the 10 bundled SemanticKITTI 08 scans | mIoU %% | Acc %% "
        "| Brier | ECE | AUROC of the error probability for wrong labels |"
        % format(metrics["map"]["queries"], ","),
        "|---|---|---|---|---|---|",
        row(metrics["input"]["description"], metrics["input"]),
        row("**map** (`%s`, the defaults)" % rule, metrics["map"]),
        "",
        "*Evidence: %s; protocol: %s. Produced by `bash scripts/regen_docs.sh` from "
        "`bash scripts/demo.sh` at commit %s, %s.*" % (
            metrics["evidence_description"], metrics["protocol"], commit, date),
    ]
    return "\n".join(lines)


def main():
    metrics_path, readme_path = sys.argv[1], sys.argv[2]
    with open(metrics_path) as f:
        metrics = json.load(f)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, check=True).stdout.strip()
    date = datetime.now(timezone.utc).strftime("%Y-%m-%d")
    with open(readme_path) as f:
        text = f.read()
    if BEGIN not in text or END not in text:
        sys.exit("readme_results.py: %s has no %s ... %s markers" % (readme_path, BEGIN, END))
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    new_text = head + BEGIN + "\n" + table(metrics, commit, date) + "\n" + END + tail
    with open(readme_path, "w") as f:
        f.write(new_text)


if __name__ == "__main__":
    main()
