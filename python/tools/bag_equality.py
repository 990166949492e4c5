"""Equality figures of the bag path (docs/ros2.md): the bundled scans written as a ROS 1 bag and
ROS 2 MCAP and sqlite3 bags by `python -m evidential_octomap.bag write`, mapped by `... bag map`,
compared leaf by leaf with the Python API's map of the same directory (and the CLI's, when
EVIDENTIAL_OCTOMAP_CLI names the binary). Two datasets: the bundled one (poses.txt as shipped)
and its copy with the poses TF carries exactly (python/tests/bag_helpers.py).

    python python/tools/bag_equality.py [SCANS]
"""
import os
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO / "python" / "tests"))

import evidential_octomap as eo  # noqa: E402
from evidential_octomap import bag  # noqa: E402
from bag_helpers import compare_leaves, tf_exact_dataset  # noqa: E402

KITTI = REPO / "data" / "semantickitti_08_first10"
CLASSES = REPO / "config" / "classes_semantickitti.yaml"


def direct_map(data, classes, scans):
    dataset = eo.Dataset.open(str(data), classes)
    tree = eo.EvidentialOcTree(0.2, classes)
    for i in range(scans):
        scan = dataset.load(i)
        tree.insert_scan(scan.points_world(), eo.derive_evidence(scan, classes.num_classes),
                         origin=scan.origin)
    return tree


def main():
    scans = int(sys.argv[1]) if len(sys.argv) > 1 else 10
    classes = eo.ClassTable.load(str(CLASSES))
    cli = os.environ.get("EVIDENTIAL_OCTOMAP_CLI")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        datasets = {"bundled poses.txt": KITTI,
                    "poses as TF carries them": tf_exact_dataset(KITTI, tmp / "exact", classes,
                                                                 scans)}
        for label, data in datasets.items():
            reference = {"Python API": direct_map(data, classes, scans).leaves()}
            if cli:
                out = tmp / f"cli_{len(rows)}"
                subprocess.run([cli, "map", "--data", str(data), "--classes", str(CLASSES),
                                "--out", str(out), "--scans", str(scans), "--no-render", "-q",
                                "--no-calibration"], check=True, capture_output=True)
                reference["CLI"] = eo.load(out / "map.ot").leaves()
            for fmt, kind in (("ROS 1", dict(ros2=False)), ("ROS 2 mcap", dict(storage="mcap")),
                              ("ROS 2 sqlite3", dict(storage="sqlite3"))):
                path = tmp / f"bag_{len(rows)}" / ("b.bag" if fmt == "ROS 1" else "b")
                path.parent.mkdir()
                bag.write_bag(data, path, classes, bag.WriteOptions(scans=scans, **kind))
                leaves = bag.map_bag(path, classes, bag.MapOptions(
                    topic="/velodyne_points/evidence")).tree.leaves()
                for name, ref in reference.items():
                    f = compare_leaves(ref, leaves)
                    rows.append((label, fmt, name, f))
    print("| poses | bag | vs | leaves (reference / bag) | only in one | labels differ | "
          "max belief diff | max u diff | max occupancy diff |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for label, fmt, name, f in rows:
        a, b = f["leaves"]
        print(f"| {label} | {fmt} | {name} | {a:,} / {b:,} | {a + b - 2 * f['common']:,} | "
              f"{f['labels_differ']:,} | {f['belief']:.1e} | {f['uncertainty']:.1e} | "
              f"{f['occupancy']:.1e} |")


if __name__ == "__main__":
    main()
