"""Maps the bundled SemanticKITTI scans, prints the metrics. Args: [out.ot] [number of scans].
The evidence is DERIVED from the network's hard labels (onehot, E = 20)."""
import sys
from pathlib import Path

import numpy as np
import evidential_octomap as eo

data = Path(__file__).resolve().parents[1] / "data" / "semantickitti_08_first10"
classes = eo.bundled_class_table("semantickitti")
count = int(sys.argv[2]) if len(sys.argv) > 2 else 10
scans = [eo.Dataset.open(str(data), classes).load(i) for i in range(count)]
tree = eo.EvidentialOcTree(0.2, classes)
for scan in scans:
    tree.insert_scan(scan.points_world(), eo.derive_evidence(scan, len(classes)), origin=scan.origin)
tree.save(sys.argv[1] if len(sys.argv) > 1 else "map.ot")
points, gt = np.concatenate([s.points_world() for s in scans]), np.concatenate([s.gt for s in scans])
m = eo.evaluate_map(tree, points, gt, classes.ignore_class)
q = m.quality  # every query counts; one without evidence is wrong
print(f"{tree.num_leaves} leaves; coverage {m.semantic_coverage:.1%} mIoU {q.miou_all:.1%} Acc {q.acc_all:.1%}")
