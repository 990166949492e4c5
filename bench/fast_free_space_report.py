#!/usr/bin/python3
"""Writes docs/experiments/fast_free_space.md: what fast free space (off by default and in the
live profile, config/mapping_live.yaml) saves and costs in the live profile.

Speed: evidential_sequence_bench with plain OctoMap, the live profile and the live profile
with fast_free_space, interleaved in one process (2 threads, OMP_WAIT_POLICY=passive as
launch/mapping.launch sets it), max range 50 m, on the bundled scans forth and back (30 inserts:
first pass 0-9, steady state 10-29) and on a SYNTHETIC generated forest (os1-64, driven out and
back, 60 scans: first 10, then the rest). Quality: `evidential_octomap compare` of the two on the
bundled scans, both protocols, one-hot (derived) and learned evidence.

    bench/fast_free_space_report.py [BUILD_DIR=build/core]   # ~6 min on 2 cores
"""
import csv
import datetime
import json
import os
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "experiments" / "fast_free_space.md"
COMMAND = "bench/fast_free_space_report.py"
METHODS = ["plain", "live", "live_fast_free_space"]
STAGES = ["cpu_ms_rays", "cpu_ms_kernel", "cpu_ms_update"]
LIVE = "length_scale=0.2:ds_multiplier=2:evidence_floor=0.01:semantic_occupied_only=true"
FOREST = ["generate", "--scene", "forest", "--sensor", "os1-64", "--scans", "60", "--seed", "3",
          "--route", "out-and-back", "--route-length", "60"]


def load() -> str:
    return " ".join(pathlib.Path("/proc/loadavg").read_text().split()[:3])


def sequence(build: pathlib.Path, csv_path: str, args: list) -> str:
    env = dict(os.environ, OMP_NUM_THREADS="2", OMP_WAIT_POLICY="passive")
    before = load()
    subprocess.run([str(build / "bench" / "evidential_sequence_bench"), *args, "--methods",
                    ",".join(METHODS), "--csv", csv_path], cwd=ROOT, env=env, check=True,
                   capture_output=True)
    return f"{before} → {load()}"


def phases(csv_path: str, first: int) -> dict:
    """{(phase, method): (cpu ms, wall ms, stage ms...) mean per scan}"""
    rows = {}
    with open(csv_path) as f:
        for r in csv.DictReader(f):
            phase = "first pass" if int(r["step"]) < first else "steady state"
            rows.setdefault((phase, r["method"]), []).append(r)
    return {k: [sum(float(r[c]) for r in v) / len(v) for c in ["cpu_ms", "wall_ms", *STAGES]]
            for k, v in rows.items()}


def speed_table(name: str, m: dict, loads: str) -> list:
    lines = [f"**{name}** (load average {loads})", "",
             "| phase | settings | CPU ms/scan | CPU ratio to plain | wall ratio | ray casting ms | "
             "kernel ms | tree update ms |", "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for phase in ("first pass", "steady state"):
        plain = m[(phase, "plain")]
        for method in METHODS[1:]:
            v = m[(phase, method)]
            label = "live profile" if method == "live" else "live profile with fast_free_space"
            lines.append(f"| {phase} | {label} | {v[0]:.1f} | {v[0] / plain[0]:.3f} | "
                         f"{v[1] / plain[1]:.3f} | {v[2]:.1f} | {v[3]:.1f} | {v[4]:.1f} |")
    return lines + [""]


def quality(build: pathlib.Path) -> list:
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([str(build / "src" / "tools" / "evidential_octomap"), "compare",
                        "--data", "data/semantickitti_08_first10",
                        "--classes", "config/classes_semantickitti.yaml", "--out", out,
                        "--sources", "onehot,learned", "--protocols", "reconstruction,held-out",
                        "--no-rellis", "--max-range", "50", "--variants",
                        f"dempster:{LIVE}:fast_free_space=true", f"dempster:{LIVE}"],
                       cwd=ROOT, check=True, capture_output=True)
        result = json.loads((pathlib.Path(out) / "compare.json").read_text())
    maps = {(r["protocol"], r["evidence_source"], r["variant_id"].endswith("fast_free_space=true")): r["map"]
            for r in result["runs"]}
    lines = ["| protocol | evidence | mIoU (all) %, fast free space → every ray in full | Brier | "
             "semantic coverage |",
             "| --- | --- | --- | --- | --- |"]
    for protocol, evidence in sorted({k[:2] for k in maps}):
        a, b = maps[(protocol, evidence, True)], maps[(protocol, evidence, False)]
        lines.append(f"| {protocol} | {evidence} | {100 * a['miou_all_queries']:.2f} → "
                     f"{100 * b['miou_all_queries']:.2f} | {a['brier']:.4f} → {b['brier']:.4f} | "
                     f"{100 * a['semantic_coverage']:.1f} % → {100 * b['semantic_coverage']:.1f} % |")
    return lines


def main() -> None:
    build = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "build" / "core"
    with tempfile.TemporaryDirectory() as tmp:
        forest = os.path.join(tmp, "forest")
        subprocess.run([str(build / "src" / "tools" / "evidential_octomap"), *FOREST, "--out",
                        forest, "--quiet"], check=True, capture_output=True)
        revisit_csv, forest_csv = os.path.join(tmp, "revisit.csv"), os.path.join(tmp, "forest.csv")
        revisit_load = sequence(build, revisit_csv, [
            "--data", "data/semantickitti_08_first10", "--classes",
            "config/classes_semantickitti.yaml", "--order", "revisit", "--scans", "10",
            "--steps", "30"])
        forest_load = sequence(build, forest_csv, [
            "--data", forest, "--classes", os.path.join(forest, "classes.yaml"),
            "--order", "forward"])
        revisit, woods = phases(revisit_csv, 10), phases(forest_csv, 10)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip() or "unknown"
    lines = ["# Fast free space in the live profile", "",
             f"Generated by `{COMMAND}` (commit {commit}, {datetime.date.today().isoformat()}).",
             "", "The live profile's settings (every ray cast in full) and the same with `fast_free_space`, "
             "beside plain "
             "OctoMap (`insertPointCloud`, discretized) fed the same scans in one interleaved "
             "process: 2 threads, `OMP_WAIT_POLICY=passive` (as `launch/mapping.launch` sets it), "
             "max range 50 m, evidence derived (one-hot of the shipped predictions × 20). Ratios "
             "are sums over a phase's scans.", "",
             *speed_table("Bundled SemanticKITTI scans forth and back (30 inserts; first pass "
                          "0–9, steady state 10–29)", revisit, revisit_load),
             *speed_table("SYNTHETIC forest, os1-64, driven 60 m out and back (`evidential_octomap "
                          + " ".join(FOREST) + "`; first pass scans 0–9, steady state 10–59)",
                          woods, forest_load),
             "Map quality, `evidential_octomap compare` on the bundled scans (max range 50 m):", "",
             *quality(build), ""]
    PAGE.write_text("\n".join(lines))
    print(f"wrote {PAGE.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
