"""Uncertainty-aware semantic OctoMap from Python.

Fuses per-point semantic evidence (N x C, e >= 0, e.g. from an evidential segmentation network)
into an OctoMap whose voxels carry Dempster-Shafer belief masses and an uncertainty (Kim & Seo
2024). numpy in and out; the C++ core does the work with the GIL released.

    import evidential_octomap as eo
    tree = eo.EvidentialOcTree(0.2, eo.bundled_class_table("semantickitti"))
    tree.insert_scan(points_S, evidence, pose=T_W_S)
    answer = tree.query(points_W)   # labels, belief, uncertainty, conflict, occupied, known
    tree.save("map.ot")

Batch mapping of long sequences on Dask: ``python -m evidential_octomap.batch --help``.
ROS 1 / ROS 2 bags and a live Foxglove view, no ROS needed: ``python -m evidential_octomap.bag
--help`` (``pip install ".[bags]"``).
"""
from pathlib import Path

from ._core import (
    Calibration,
    ClassTable,
    ColorOcTree,
    Dataset,
    EvidentialOcTree,
    InsertStats,
    LearnedEvidenceModel,
    Leaves,
    LocalMap,
    TiledMap,
    ErrorDetection,
    MapMetrics,
    QualityMetrics,
    QueryResult,
    Scan,
    SemanticConfig,
    derive_evidence,
    evidence_from_logits,
    evidence_from_probabilities,
    evaluate_map,
    evaluate_input,
    evidence_is_derived,
    read_calibration,
)

__all__ = [
    "Calibration",
    "ClassTable",
    "ColorOcTree",
    "Dataset",
    "EvidentialOcTree",
    "InsertStats",
    "LearnedEvidenceModel",
    "Leaves",
    "LocalMap",
    "TiledMap",
    "ErrorDetection",
    "MapMetrics",
    "QualityMetrics",
    "QueryResult",
    "Scan",
    "SemanticConfig",
    "bundled_class_table",
    "derive_evidence",
    "evidence_from_logits",
    "evidence_from_probabilities",
    "evaluate_map",
    "evaluate_input",
    "evidence_is_derived",
    "load",
    "read_calibration",
]

try:  # built when OpenCV was found (the CLI's top-down pictures)
    from ._core import render_top_down  # noqa: F401
    __all__.append("render_top_down")
except ImportError:
    pass

_CONFIG_DIR = Path(__file__).resolve().parent / "config"


def bundled_class_table(name: str) -> ClassTable:
    """A class table shipped with the package: 'semantickitti' or 'rellis3d'."""
    path = _CONFIG_DIR / f"classes_{name}.yaml"
    if not path.is_file():
        known = sorted(p.stem[len("classes_"):] for p in _CONFIG_DIR.glob("classes_*.yaml"))
        raise ValueError(f"no bundled class table '{name}'; bundled: {', '.join(known)}")
    return ClassTable.load(str(path))


def load(path) -> EvidentialOcTree:
    """Reads an .ot map (EvidentialOcTree.load)."""
    return EvidentialOcTree.load(str(path))
