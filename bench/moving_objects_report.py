#!/usr/bin/python3
"""Markdown table of bench/moving_objects.cpp's JSON lines (one per clearing_observations value),
stamped with the commit and date. Usage: moving_objects_report.py RESULT.jsonl DATASET_NAME"""
import datetime
import json
import subprocess
import sys


def stamp() -> str:
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip() or "unknown"
    return f"commit {commit}, {datetime.datetime.utcnow():%Y-%m-%d %H:%M} UTC"


def main() -> None:
    rows = [json.loads(line) for line in open(sys.argv[1]) if line.strip()]
    print(f"SYNTHETIC sequence `{sys.argv[2]}`, lag {rows[0]['lag']} scans ({stamp()}).\n")
    print("| clearing_observations | freed swept voxels | answer the mover's class | "
          "static accuracy | dynamic accuracy | per mover (class: share) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in rows:
        movers = ", ".join(f"{m['instance']} ({m['class']}): {100 * m['ghost_share']:.1f} %"
                           for m in r["movers"])
        print(f"| {r['clearing_observations']} | {int(r['freed_voxels'])} | "
              f"{100 * r['ghost_share']:.1f} % | {100 * r['static_accuracy']:.1f} % | "
              f"{100 * r['dynamic_accuracy']:.1f} % | {movers} |")


if __name__ == "__main__":
    main()
