"""Models for clouds that carry no semantic field: the place for your own network.

A model is any callable ``model(points, fields) -> evidence``:

* ``points``: (N, 3) float32, the cloud's points in its own (sensor) frame, NaN/inf removed;
* ``fields``: every field of the PointCloud2 for those points, by name, e.g. ``fields["intensity"]``
  (N,) or an (N, k) array for a field of count k;
* returns (N, C) evidence >= 0 (C = the class table's classes). An EDL network returns its
  evidence (e.g. softplus outputs); an ordinary softmax network can return
  ``evidential_octomap.evidence_from_logits(logits)`` (the node's conversion).

Your own PyTorch or ONNX model, in a file ``my_model.py``::

    import numpy as np, torch
    net = torch.jit.load("segmenter.pt").eval()
    def evidence(points, fields):
        x = np.column_stack([points, fields["intensity"]]).astype(np.float32)
        with torch.no_grad():
            return torch.nn.functional.softplus(net(torch.from_numpy(x))).numpy()

then ``python -m evidential_octomap.bag map BAG ... --model my_model.py:evidence`` (or
``--model my_package.module:evidence``), or from Python ``map_bag(..., model=evidence)``.

The bundled example is :class:`LearnedEvidence`: the learned evidence head
(docs/learned_evidence.md) on a network's hard predictions. The bundled sequence ships those
predictions (predictions/), not the network, so :class:`DatasetPredictions` stands in for the
network: it finds a cloud's predictions by the cloud's content (x, y, z, intensity).
"""
import hashlib
import importlib
import importlib.util
from pathlib import Path
from typing import Callable, Dict

import numpy as np

from . import _core

Model = Callable[[np.ndarray, Dict[str, np.ndarray]], np.ndarray]
_PACKAGE_CONFIG = Path(__file__).resolve().parent / "config"


def content_key(points: np.ndarray, intensity) -> str:
    """Digest of a cloud's x, y, z (float32) and intensity bits."""
    h = hashlib.blake2b(digest_size=16)
    h.update(np.ascontiguousarray(points, dtype=np.float32).tobytes())
    if intensity is not None:
        h.update(np.ascontiguousarray(intensity, dtype=np.float32).tobytes())
    return h.hexdigest()


class DatasetPredictions:
    """Hard predictions (N,) int32 of a cloud, looked up in a SemanticKITTI-layout directory.

    Stands in for a segmentation network in the bundled example: each scan of the directory is
    keyed by its points and remission, and a cloud with exactly those points gets that scan's
    predictions/ classes. A cloud that is no scan of the directory raises LookupError.
    """

    def __init__(self, data_dir, classes):
        dataset = _core.Dataset.open(str(data_dir), classes)
        if not dataset.has_predictions:
            raise RuntimeError(f"{data_dir}: no predictions/ to stand in for the network")
        self._by_key = {}
        for i in range(len(dataset)):
            scan = dataset.load(i)
            self._by_key[content_key(scan.points, scan.remission)] = scan.predicted
        self.source = str(data_dir)

    def __call__(self, points, fields) -> np.ndarray:
        key = content_key(points, fields.get("intensity"))
        if key not in self._by_key:
            raise LookupError(f"the cloud ({len(points)} points) is no scan of {self.source}: "
                              "its predictions are unknown")
        return self._by_key[key]


class LearnedEvidence:
    """The learned evidence head as a model: evidence of a cloud from its geometry, intensity
    and a network's hard predictions (``predict(points, fields) -> (N,) int32``)."""

    def __init__(self, model_path, predict: Model):
        self.model = _core.LearnedEvidenceModel.load(str(model_path))
        self.predict = predict
        self.description = (f"learned (cross-fitted): {Path(model_path).name} on the hard "
                            f"predictions of {getattr(predict, 'source', predict)}")

    def __call__(self, points, fields) -> np.ndarray:
        predicted = np.ascontiguousarray(self.predict(points, fields), dtype=np.int32)
        intensity = fields.get("intensity")
        if intensity is not None:
            intensity = np.ascontiguousarray(intensity, dtype=np.float32).reshape(-1)
        return self.model.evidence(np.ascontiguousarray(points, dtype=np.float32), intensity,
                                   predicted)


def default_learned_model(classes_path, classes) -> Path:
    """<class table's directory>/learned/<dataset>.model (as the CLI), else the bundled one."""
    beside = Path(classes_path).resolve().parent / "learned" / f"{classes.dataset}.model"
    if beside.is_file():
        return beside
    bundled = _PACKAGE_CONFIG / "learned" / f"{classes.dataset}.model"
    if bundled.is_file():
        return bundled
    raise RuntimeError(f"no learned model for dataset '{classes.dataset}' ({beside} or "
                       f"{bundled}); pass --learned-model")


def load_callable(spec: str) -> Model:
    """'path/to/file.py:function' or 'package.module:function' -> the callable."""
    target, sep, name = spec.rpartition(":")
    if not sep or not target or not name:
        raise ValueError(f"--model '{spec}': expected 'learned', 'file.py:function' or "
                         "'module:function'")
    if target.endswith(".py"):
        path = Path(target)
        if not path.is_file():
            raise ValueError(f"--model '{spec}': no file {path}")
        module_spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(module_spec)
        module_spec.loader.exec_module(module)
    else:
        module = importlib.import_module(target)
    fn = getattr(module, name, None)
    if not callable(fn):
        raise ValueError(f"--model '{spec}': {target} has no callable '{name}'")
    return fn
