"""sensor_msgs/PointCloud2 -> points and per-point evidence, by the ROS node's field rules.

This mirrors ``fromPointCloud2`` of src/ros/conversions.cpp (the ROS 1 node's reader): the same
fields, the same order of preference, the same checks and the same messages, vectorised with
numpy. The number conversions themselves (logits, probabilities) are the core's, through the
bindings, so there is one implementation of the maths.

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
SEMANTIC_FIELDS = ("evidence", "alpha", "logits", "probabilities", "label")


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


def _field_list(msg) -> str:
    return ", ".join(f.name for f in msg.fields) or "(none)"


def _find(msg, name):
    for f in msg.fields:
        if f.name == name:
            return f
    return None


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


def _channels(msg, points: _Points, base: str, C: int):
    """(N, C) values of `base` (one field of count C or base_0 .. base_{C-1}) in the fields'
    type (float32 or float64), "absent", or an error string."""
    is_float = (FLOAT32, FLOAT64)
    f = _find(msg, base)
    if f is not None:
        if f.datatype not in is_float:
            return f"field '{base}' must be float32 (or float64), is {_type_name(f.datatype)}"
        if int(f.count) != C:
            return f"field '{base}' has count {f.count}, expected C = {C} (num_classes)"
        err = _check_field(f, msg.point_step)
        if err:
            return err
        return points.read(f.offset, f.datatype, C).reshape(-1, C)
    if _find(msg, base + "_0") is None:
        return "absent"
    columns = []
    for c in range(C):
        name = f"{base}_{c}"
        f = _find(msg, name)
        if f is None:
            return (f"field '{name}' is missing: per-class fields need {base}_0 .. {base}_{C - 1} "
                    f"(C = {C})")
        if f.datatype not in is_float:
            return f"field '{name}' must be float32 (or float64), is {_type_name(f.datatype)}"
        err = _check_field(f, msg.point_step)
        if err:
            return err
        columns.append(points.read(f.offset, f.datatype))
    if _find(msg, f"{base}_{C}") is not None:
        return (f"field '{base}_{C}' exists: the cloud has more than C = {C} (num_classes) "
                "channels")
    return np.stack(columns, axis=1)


def _first_bad(bad: np.ndarray, index: np.ndarray):
    """(point index, class) of the first True of an (N, C) mask, row-major."""
    row, col = np.unravel_index(int(np.argmax(bad.ravel())), bad.shape)
    return int(index[row]), int(col)


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
    C = int(num_classes)
    if C <= 0:
        raise CloudError("num_classes must be positive")
    if input not in INPUTS:
        raise CloudError(f"input_type '{input}' is unknown; use " + ", ".join(INPUTS))
    n_points = int(msg.width) * int(msg.height)
    if n_points == 0:
        raise CloudError("cloud has zero points")
    if msg.point_step == 0:
        raise CloudError("point_step is 0")
    if msg.row_step < msg.width * msg.point_step:
        raise CloudError(f"row_step {msg.row_step} < width {msg.width} x point_step "
                         f"{msg.point_step}")
    needed = msg.row_step * (msg.height - 1) + msg.width * msg.point_step
    if len(msg.data) < needed:
        raise CloudError(f"truncated data: {len(msg.data)} bytes for {msg.width} x {msg.height} "
                         f"points need {needed}")
    points = _Points(msg)

    xyz = []
    for axis in "xyz":
        f = _find(msg, axis)
        if f is None:
            raise CloudError(f"missing field '{axis}' (fields: {_field_list(msg)})")
        if f.datatype not in (FLOAT32, FLOAT64):
            raise CloudError(f"field '{axis}' must be float32 or float64, is "
                             f"{_type_name(f.datatype)}")
        err = _check_field(f, msg.point_step)
        if err:
            raise CloudError(err)
        xyz.append(points.read(f.offset, f.datatype).astype(np.float64))
    xyz = np.stack(xyz, axis=1)

    # --- which semantic field
    kind, values, label_field = None, None, None
    order = SEMANTIC_FIELDS if input == "auto" else ((input,) if input != "none" else ())
    for base in order:
        if base == "label":
            f = _find(msg, "label")
            if f is None:
                continue
            err = _check_field(f, msg.point_step)
            if err:
                raise CloudError(err)
            kind, label_field = "label", f
            break
        got = _channels(msg, points, base, C)
        if isinstance(got, str):
            if got == "absent":
                continue
            raise CloudError(got)
        kind, values = base, got
        break
    if kind is None and input not in ("auto", "none"):
        if input == "label":
            raise CloudError(f"missing field 'label' (fields: {_field_list(msg)})")
        raise CloudError(f"missing field '{input}' (float32, count {C}) or '{input}_0'.. "
                         f"(fields: {_field_list(msg)})")

    # --- points: coordinates within float range (NaN/inf dropped)
    keep = (np.abs(xyz) <= _FLOAT_MAX).all(axis=1)
    nonfinite = int(n_points - keep.sum())
    if not keep.any():
        raise CloudError(f"cloud has no finite points ({nonfinite} NaN/inf)")
    index = np.flatnonzero(keep)

    evidence = None
    if kind in ("evidence", "alpha"):
        v = values if nonfinite == 0 else values[keep]  # (float32 a - 1 rounds as in float64)
        e = v - 1.0 if kind == "alpha" else v
        valid = (e >= 0) & (e <= _FLOAT_MAX)  # NaN fails both
        if not valid.all():
            i, c = _first_bad(~valid, index)
            shown = values[i, c]
            rule = ("alpha must be finite and >= 1, within float range" if kind == "alpha"
                    else "evidence must be finite and >= 0, within float range")
            raise CloudError(f"point {i}: {kind} of class {c} is {shown:g} ({rule})")
        evidence = np.ascontiguousarray(e, dtype=np.float32)
    elif kind in ("logits", "probabilities"):
        raw = np.ascontiguousarray(values[keep], dtype=np.float32)
        try:
            if kind == "logits":
                evidence = _core.evidence_from_logits(raw, logit_transform, probability_magnitude)
            else:
                evidence = _core.evidence_from_probabilities(raw, probability_magnitude)
        except ValueError as e:  # "point <row>: ..." -> the message's point index
            text = str(e)
            row = int(text.split(":")[0].split()[1])
            raise CloudError(f"point {int(index[row])}:{text.split(':', 1)[1]}") from None
    elif kind == "label":
        evidence = _labels_to_evidence(points.read(label_field.offset, label_field.datatype)[keep],
                                       index, C, label_magnitude, raw_label_table)
    elif kind is None and input == "none":
        evidence = np.zeros((len(index), C), dtype=np.float32)

    source = {None: "none (occupancy only)" if input == "none" else "none",
              "evidence": f"evidence[{C}]", "alpha": f"alpha[{C}]",
              "logits": f"logits[{C}] ({logit_transform})",
              "probabilities": f"probabilities[{C}]", "label": "label"}[kind]
    # Every field for a model, only when the cloud has no semantic field (a model's input).
    fields = ({name: a[keep] for name, a in all_fields(msg, points).items()}
              if kind is None and input == "auto" else {})
    return Cloud(points=xyz[keep].astype(np.float32), evidence=evidence, source=source,
                 nonfinite_points=nonfinite, fields=fields)


def _labels_to_evidence(values, index, C, magnitude, raw_label_table) -> np.ndarray:
    v = values.astype(np.float64)
    bad = ~np.isfinite(v) | (v != np.floor(v)) | (v < 0)
    if bad.any():
        i = int(np.argmax(bad))
        raise CloudError(f"point {int(index[i])}: label {v[i]:g} is not a non-negative integer")
    limit = 4294967296.0 if raw_label_table is not None else float(C)
    if (v >= limit).any():
        i = int(np.argmax(v >= limit))
        what = (" is beyond the 32-bit raw ids" if raw_label_table is not None
                else f" is outside [0, {C})")
        raise CloudError(f"point {int(index[i])}: label {v[i]:.17g}{what}")
    labels = v.astype(np.int64)
    if raw_label_table is not None:
        try:
            labels = np.asarray(raw_label_table.classes_of_raw(labels.astype(np.uint32)),
                                dtype=np.int64)
        except (IndexError, ValueError, RuntimeError) as e:  # name the first such point
            for i, raw in enumerate(labels.astype(np.uint32)):
                try:
                    raw_label_table.classes_of_raw(np.array([raw], dtype=np.uint32))
                except (IndexError, ValueError, RuntimeError) as first:
                    raise CloudError(f"point {int(index[i])}: {first}") from None
            raise CloudError(str(e)) from None
    if (labels >= C).any():
        i = int(np.argmax(labels >= C))
        raise CloudError(f"point {int(index[i])}: label {int(labels[i])} is outside [0, {C})")
    evidence = np.zeros((len(labels), C), dtype=np.float32)
    evidence[np.arange(len(labels)), labels] = magnitude
    return evidence


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
