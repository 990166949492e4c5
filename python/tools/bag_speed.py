"""Speed of the bag path beside the CLI on the same scans (docs/ros2.md).

Writes the bundled scans as a ROS 2 MCAP bag and a ROS 1 bag, then alternates, ROUNDS times,
`python -m evidential_octomap.bag map` on each bag (evidence topic, no pictures) and
`evidential_octomap map` on the directory (--no-calibration --no-render, the same onehot E = 20
evidence): wall and CPU (user + sys) of each process, scans/s = scans / wall, and the insert time
(the bag summary's `insert`, the CLI's ms_per_scan). Prints `uptime` before and after.

    EVIDENTIAL_OCTOMAP_CLI=build/core/src/tools/evidential_octomap \\
        python python/tools/bag_speed.py [SCANS] [ROUNDS]
"""
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
KITTI = REPO / "data" / "semantickitti_08_first10"
CLASSES = REPO / "config" / "classes_semantickitti.yaml"


def timed(cmd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main():
    scans = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    cli = os.environ.get("EVIDENTIAL_OCTOMAP_CLI",
                         str(REPO / "build" / "core" / "src" / "tools" / "evidential_octomap"))
    print("uptime before:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    py = [sys.executable, "-m", "evidential_octomap.bag"]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        bags = {"ROS 2 mcap": tmp / "mcap", "ROS 1": tmp / "k.bag"}
        for name, path in bags.items():
            flag = ["--ros1"] if name == "ROS 1" else ["--ros2", "--storage", "mcap"]
            subprocess.run(py + ["write", str(KITTI), str(path), *flag, "--classes", str(CLASSES),
                                 "--scans", str(scans), "-q"], check=True, capture_output=True)
        for r in range(rounds):
            for name, path in bags.items():
                out = tmp / f"bag_{r}_{len(rows)}"
                wall, cpu = timed(py + ["map", str(path), "--classes", str(CLASSES), "--out",
                                        str(out), "--topic", "/velodyne_points/evidence",
                                        "--no-render", "-q"])
                s = json.loads((out / "summary.json").read_text())
                rows.append((r + 1, f"bag map ({name})", wall, cpu, s["scans_mapped"],
                             s["seconds"]["insert"], s["seconds"]["total"]))
            out = tmp / f"cli_{r}"
            wall, cpu = timed([cli, "map", "--data", str(KITTI), "--classes", str(CLASSES),
                               "--out", str(out), "--scans", str(scans), "--no-render", "-q",
                               "--no-calibration"])
            m = json.loads((out / "metrics.json").read_text())
            ms = m.get("ms_per_scan") or m.get("timing", {}).get("ms_per_scan", [])
            rows.append((r + 1, "evidential_octomap map (CLI)", wall, cpu, scans,
                         sum(ms) / 1000 if ms else float("nan"), None))
    print("uptime after:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    print("\n| round | run | wall | CPU (user + sys) | scans/s (wall) | insert | in-process total |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r, name, wall, cpu, n, insert, total in rows:
        print(f"| {r} | {name} | {wall:.1f} s | {cpu:.1f} s | {n / wall:.2f} | {insert:.1f} s | "
              + (f"{total:.1f} s |" if total is not None else "- |"))


if __name__ == "__main__":
    main()
