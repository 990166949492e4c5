"""sensor_msgs/PointCloud2 -> points and per-point evidence, by the ROS node's field rules.

The reading is the core's (``readPointCloud2`` of include/evidential_octomap/pointcloud2_reader.h,
which the ROS 1 node calls too): the same fields, order of preference, checks and messages, in
C++ with the interpreter released.

Semantic fields (C = number of classes), ``input="auto"`` takes the first present of:

=================  ==================================================================
``evidence``       float32/float64, one field of count C or ``evidence_0 .. evidence_{C-1}``
``alpha``          the same forms; evidence e = alpha - 1
``logits``         the same forms; e by ``logit_transform`` (softmax, exp, softplus)
``probabilities``  the same forms; confidence-scaled evidence of magnitude E
``label``          any integer or float type; one-hot evidence of ``label_magnitude``
=================  ==================================================================

Works for any ``point_step``, ``row_step`` padding, ``height`` (organised clouds) and byte order.
Points with a coordinate that is NaN, inf or beyond float range are dropped and counted.
A message the rules refuse raises :class:`CloudError` saying what is wrong.

Works on any object with the message's attributes (``fields`` of ``name, offset, datatype,
count``; ``height, width, point_step, row_step, is_bigendian, data``), e.g. rosbags' messages.
"""
from dataclasses import dataclass, field
from typing import Dict, Optional

import numpy as np

from . import _core

INT8, UINT8, INT16, UINT16, INT32, UINT32, FLOAT32, FLOAT64 = range(1, 9)
_TYPES = {INT8: "i1", UINT8: "u1", INT16: "i2", UINT16: "u2", INT32: "i4", UINT32: "u4",
          FLOAT32: "f4", FLOAT64: "f8"}
_TYPE_NAMES = ["?", "int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"]
_FLOAT_MAX = float(np.finfo(np.float32).max)
INPUTS = ("auto", "evidence", "alpha", "logits", "probabilities", "label", "none")


class CloudError(ValueError):
    """A PointCloud2 the node's field rules refuse (the message says why)."""


@dataclass
class Cloud:
    """A decoded cloud: points in the message's frame and their evidence."""
    points: np.ndarray                # (N, 3) float32
    evidence: Optional[np.ndarray]    # (N, C) float32; None when the cloud has no semantic field
    source: str                       # which field was read, e.g. "evidence[20]", "label"
    nonfinite_points: int = 0         # dropped for NaN/inf coordinates
    fields: Dict[str, np.ndarray] = field(default_factory=dict)  # every field, kept points only


def _type_name(datatype: int) -> str:
    return _TYPE_NAMES[datatype] if 0 <= datatype <= 8 else "?"


def _check_field(f, point_step: int) -> str:
    if f.datatype not in _TYPES:
        return f"field '{f.name}' has unknown datatype {f.datatype}"
    count = max(int(f.count), 1)
    size = np.dtype(_TYPES[f.datatype]).itemsize
    if f.offset + size * count > point_step:
        return (f"field '{f.name}' (offset {f.offset}, {count} x {_type_name(f.datatype)}) "
                f"does not fit point_step {point_step}")
    return ""


class _Points:
    """The message's points as an (N, point_step) byte matrix (row padding removed)."""

    def __init__(self, msg):
        data = np.frombuffer(memoryview(msg.data), dtype=np.uint8)
        rows = data[: msg.row_step * msg.height].reshape(msg.height, msg.row_step) \
            if msg.height * msg.row_step <= data.size else None
        if rows is None:  # the last row may lack its padding
            rows = np.stack([data[v * msg.row_step: v * msg.row_step + msg.width * msg.point_step]
                             for v in range(msg.height)])
        self.bytes = np.ascontiguousarray(rows[:, : msg.width * msg.point_step]).reshape(
            msg.height * msg.width, msg.point_step)
        self.order = ">" if msg.is_bigendian else "<"

    def read(self, offset: int, datatype: int, count: int = 1) -> np.ndarray:
        """(N,) or (N, count) values of a field, in the host's byte order."""
        dt = np.dtype(self.order + _TYPES[datatype])
        raw = self.bytes[:, offset: offset + dt.itemsize * count]
        values = np.ascontiguousarray(raw).view(dt)
        values = values.astype(dt.newbyteorder("="), copy=False)
        return values if count > 1 else values[:, 0]


def all_fields(msg, points: Optional[_Points] = None) -> Dict[str, np.ndarray]:
    """Every readable field of the message as (N,) or (N, count) arrays (all points)."""
    points = points or _Points(msg)
    out = {}
    for f in msg.fields:
        if not _check_field(f, msg.point_step):
            out[f.name] = points.read(f.offset, f.datatype, max(int(f.count), 1))
    return out


def decode(msg, num_classes: int, input: str = "auto",
           label_magnitude: float = _core.EVIDENCE_MAGNITUDE, logit_transform: str = "softmax",
           probability_magnitude: float = _core.EVIDENCE_MAGNITUDE,
           raw_label_table=None) -> Cloud:
    """Reads points and evidence of a PointCloud2 by the node's rules (see the module's doc).

    With ``input="auto"`` a cloud without any semantic field is returned with ``evidence=None``
    (the caller may run a model on it); an explicit input that is missing raises CloudError.
    ``raw_label_table``: a ClassTable whose learning map turns raw ``label`` ids into classes.
    """
    fields = [(f.name, int(f.offset), int(f.datatype), int(f.count)) for f in msg.fields]
    data = np.frombuffer(memoryview(msg.data), dtype=np.uint8)
    try:
        points, evidence, source, nonfinite = _core.read_pointcloud2(
            fields, data, int(msg.height), int(msg.width), int(msg.point_step),
            int(msg.row_step), bool(msg.is_bigendian), int(num_classes), input,
            label_magnitude, logit_transform, probability_magnitude, raw_label_table)
    except ValueError as e:
        raise CloudError(str(e)) from None
    model_input = {}
    if evidence is None:  # every field of the kept points, for a model
        every = all_fields(msg)
        keep = np.ones(int(msg.width) * int(msg.height), dtype=bool)
        for axis in "xyz":
            keep &= np.abs(every[axis].astype(np.float64)) <= _FLOAT_MAX
        model_input = {name: a[keep] for name, a in every.items()}
    return Cloud(points=points, evidence=evidence, source=source, nonfinite_points=nonfinite,
                 fields=model_input)


def pack(columns: Dict[str, np.ndarray]) -> tuple:
    """Packs float32 columns ((N,) or (N, k)) into little-endian point bytes.

    Returns (fields, point_step, data): fields as (name, offset, datatype, count) rows.
    """
    descr = []
    for name, a in columns.items():
        a = np.asarray(a)
        shape = () if a.ndim == 1 else (a.shape[1],)
        descr.append((name, "<f4", shape))
    dtype = np.dtype(descr)
    n = len(next(iter(columns.values())))
    data = np.empty(n, dtype=dtype)
    fields = []
    for name, a in columns.items():
        data[name] = a
        count = 1 if np.asarray(a).ndim == 1 else np.asarray(a).shape[1]
        fields.append((name, dtype.fields[name][1], FLOAT32, count))
    return fields, dtype.itemsize, data.view(np.uint8).reshape(-1)


_DATATYPES = {np.dtype("<f4"): FLOAT32, np.dtype("<f8"): FLOAT64, np.dtype("<i4"): INT32,
              np.dtype("<u4"): UINT32, np.dtype("<i2"): INT16, np.dtype("<u2"): UINT16,
              np.dtype("i1"): INT8, np.dtype("u1"): UINT8}


def pack_typed(columns: Dict[str, np.ndarray]) -> tuple:
    """As :func:`pack`, for columns of any PointField type (float32, int32, uint32, ...), each
    kept in its own dtype (little-endian)."""
    descr = []
    for name, a in columns.items():
        a = np.asarray(a)
        dt = a.dtype.newbyteorder("<") if a.dtype.itemsize > 1 else a.dtype
        if dt not in _DATATYPES:
            raise ValueError(f"column '{name}' has dtype {a.dtype}, which PointField lacks")
        descr.append((name, dt, () if a.ndim == 1 else (a.shape[1],)))
    dtype = np.dtype(descr)
    n = len(next(iter(columns.values())))
    data = np.empty(n, dtype=dtype)
    fields = []
    for (name, dt, shape) in descr:
        data[name] = columns[name]
        fields.append((name, dtype.fields[name][1], _DATATYPES[dt], shape[0] if shape else 1))
    return fields, dtype.itemsize, data.view(np.uint8).reshape(-1)
