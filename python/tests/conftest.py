"""Shared fixtures: the bundled SemanticKITTI scans and a small synthetic scene."""
from pathlib import Path

import numpy as np
import pytest

import evidential_octomap as eo

REPO = Path(__file__).resolve().parents[2]
KITTI = REPO / "data" / "semantickitti_08_first10"


@pytest.fixture(scope="session")
def kitti_classes():
    return eo.ClassTable.load(str(REPO / "config" / "classes_semantickitti.yaml"))


@pytest.fixture(scope="session")
def kitti(kitti_classes):
    return eo.Dataset.open(str(KITTI), kitti_classes)


@pytest.fixture(scope="session")
def kitti_scans(kitti, kitti_classes):
    """Scans 0-2 with their onehot evidence (derived from the network's hard labels)."""
    scans = [kitti.load(i) for i in range(3)]
    return [(s, eo.derive_evidence(s, kitti_classes.num_classes)) for s in scans]


def wall(x=4.0, label=1, num_classes=3, magnitude=8.0):
    """A synthetic wall of points at distance x, all with evidence for `label`."""
    y, z = np.meshgrid(np.arange(-1.0, 1.0, 0.05), np.arange(0.0, 1.0, 0.05))
    points = np.stack([np.full(y.size, x), y.ravel(), z.ravel()], axis=1).astype(np.float32)
    evidence = np.full((len(points), num_classes), 0.5, dtype=np.float32)
    evidence[:, label] = magnitude
    return points, evidence
