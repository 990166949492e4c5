#!/usr/bin/env python3
"""Prints the key ratios of two evidential_bench JSON files side by side.

    python3 bench/compare_summary.py OLD.json NEW.json

Used by scripts/bench.sh so that a change that makes something slower or bigger shows up in one
run. Times and ratios: lower is better; Hz and speed-ups: higher is better.
"""
import json
import sys


def higher_is_better(key):
    return key.startswith("hz_") or key.startswith("speedup_")


def setup_value(setup, key):
    # Files written before "quick" was recorded were full runs.
    return setup.get(key, False if key == "quick" else None)


def main():
    if len(sys.argv) != 3:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        old_doc = json.load(f)
    with open(sys.argv[2]) as f:
        new_doc = json.load(f)
    old, new = old_doc.get("summary", {}), new_doc.get("summary", {})
    old_setup, new_setup = old_doc.get("setup", {}), new_doc.get("setup", {})
    differ = [k for k in ("scans", "resolution", "num_classes", "points_per_scan", "quick")
              if setup_value(old_setup, k) != setup_value(new_setup, k)]
    if differ:
        print("WARNING: the runs differ in " + ", ".join(
            f"{k} ({old_setup.get(k)} vs {new_setup.get(k)})" for k in differ) +
              ": the figures below are not comparable")
    keys = [k for k in new if k in old] + [k for k in new if k not in old]
    width = max(len(k) for k in keys) if keys else 10
    print(f"{'metric':<{width}}  {'baseline':>12}  {'now':>12}  {'change':>8}")
    worse = 0
    for k in keys:
        a, b = old.get(k), new.get(k)
        if a is None or b is None or a == 0:
            print(f"{k:<{width}}  {'-' if a is None else f'{a:.4g}':>12}  {'-' if b is None else f'{b:.4g}':>12}")
            continue
        change = (b - a) / abs(a) * 100.0
        bad = (change < -10.0) if higher_is_better(k) else (change > 10.0)
        worse += bad
        flag = "  <-- worse" if bad else ""
        print(f"{k:<{width}}  {a:>12.4g}  {b:>12.4g}  {change:>+7.1f}%{flag}")
    if worse:
        print(f"{worse} metric(s) more than 10 % worse than the baseline "
              "(check the machine load before blaming the code)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
