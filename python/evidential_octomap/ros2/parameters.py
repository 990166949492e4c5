"""The node's parameters without ROS: names, defaults, descriptions and the checks that refuse a
bad value with its reason. The semantic settings come from the core's one settings list (their
ROS 1 ~param names, "/" written "." as ROS 2 nests parameters) and are checked by the core's own
validation; the node's own parameters keep the ROS 1 node's names (docs/ros.md)."""
import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

from .. import _core, pointcloud2

# Number checks of the node's own parameters: (test, words)
_POSITIVE = (lambda v: math.isfinite(v) and v > 0, "finite and > 0")
_NON_NEGATIVE = (lambda v: math.isfinite(v) and v >= 0, "finite and >= 0")
_FINITE = (lambda v: math.isfinite(v), "finite")
_AT_LEAST_ONE = (lambda v: v >= 1, ">= 1")
_NOT_NAN = (lambda v: not math.isnan(v), "a number (not NaN; +-inf for no bound)")


@dataclass
class Parameter:
    name: str                     # ROS 2 name
    default: Any
    description: str
    read_only: bool = False       # fixed at start-up (what a voxel means, where the map is)
    check: Optional[tuple] = None  # (test, words) for numbers
    choices: List[str] = field(default_factory=list)
    setting: Optional[str] = None  # SemanticConfig field name, for the core's settings
    range_text: str = ""


def ros2_name(ros1_name: str) -> str:
    return ros1_name.replace("/", ".")


def _node_parameters() -> List[Parameter]:
    P = Parameter
    return [
        P("classes", "", "class table YAML (names, colours, learning map); '' = the bundled "
          "SemanticKITTI table", read_only=True),
        P("num_classes", 0, "0: from the class table; otherwise must equal it", read_only=True),
        P("frame_id", "map", "map frame: clouds are transformed into it at their stamp",
          read_only=True),
        P("resolution", 0.2, "leaf size [m] (a map_file brings its own)", read_only=True,
          check=_POSITIVE),
        P("map_file", "", "map loaded at start-up: an .ot of the same classes", read_only=True),
        P("calibration_file", "", "a file of `evidential_octomap calibrate`: its read-out cap "
          "and error model (error_probability becomes the model's)", read_only=True),
        P("model", "", "for clouds without a semantic field (raw LiDAR): 'file.py:function' or "
          "'module:function', (points, fields) -> (N, C) evidence (models.py)", read_only=True),
        P("cloud_in_qos", "sensor_data", "QoS of cloud_in: sensor_data (best effort, keep the "
          "last 5, what LiDAR drivers offer) or reliable (every cloud of a reliable publisher; "
          "Fast DDS delivers large clouds best effort rarely, docs/ros2.md)", read_only=True,
          choices=["sensor_data", "reliable"]),
        P("input_type", "auto", "semantic field of cloud_in (auto: the first present of "
          "evidence, alpha, logits, probabilities, label)", choices=list(pointcloud2.INPUTS)),
        P("label_evidence", float(_core.EVIDENCE_MAGNITUDE), "one-hot evidence of a `label` "
          "field's class", check=_POSITIVE),
        P("label_is_raw", False, "`label` holds raw dataset ids (the class table's learning map)"),
        P("logit_transform", "softmax", "logits -> evidence", choices=["softmax", "exp",
                                                                       "softplus"]),
        P("probability_evidence", float(_core.EVIDENCE_MAGNITUDE), "E of probabilities and "
          "softmax logits", check=_POSITIVE),
        P("publish_rate", 1.0, "map views at most this often [Hz]; <= 0: after every cloud",
          check=_FINITE),
        P("insert_queue_size", 1, "clouds waiting for the insertion thread; when full the "
          "oldest is dropped (counted on the status topic)", check=_AT_LEAST_ONE),
        P("transform_timeout", 0.5, "how long a cloud waits for its transform [s]",
          check=_NON_NEGATIVE),
        P("tf_cache_time", 10.0, "/tf kept for lookups [s] (tf2's cache time)", check=_POSITIVE),
        P("occupancy_min_z", -math.inf, "leaves in projected_map from this height [m]",
          check=_NOT_NAN),
        P("occupancy_max_z", math.inf, "leaves in projected_map up to this height [m]",
          check=_NOT_NAN),
        P("foxglove_port", -1, "> 0: serve the map to Foxglove on this port of 127.0.0.1 (0: a "
          "free port, said in the log; -1: off); foxglove-sdk, the bag mapper's view",
          read_only=True),
        P("save_path", "map.ot", "where ~/save_map writes the map (.ot, and the occupancy .bt "
          "beside it); relative: from the node's working directory"),
        P("autosave_period", 0.0, "every this many seconds the map, when it changed, is written "
          "atomically to autosave_path (0: off)", check=_NON_NEGATIVE),
        P("autosave_path", "", "'' = $ROS_HOME (~/.ros)/evidential_octomap/<node name>"
          ".autosave.ot", read_only=True),
        P("resume_from_autosave", True, "with autosave on: start from autosave_path when it "
          "exists", read_only=True),
        P("sensor_model.hit", 0.7, "P(occupied | hit), in [0.5, 0.999]"),
        P("sensor_model.miss", 0.4, "P(occupied | miss), in [0.001, 0.5]"),
        P("sensor_model.min", 0.12, "clamping threshold min, in [0.001, 0.5]"),
        P("sensor_model.max", 0.97, "clamping threshold max, in [0.5, 0.999]"),
    ]


def _setting_parameters() -> List[Parameter]:
    out = []
    for s in _core.settings():
        text = s["range_text"] if s["type"] != "string" else "one of " + ", ".join(s["choices"])
        out.append(Parameter(ros2_name(s["ros_name"]), s["default"],
                             f"{s['help']} ({s['type']}, {text}; {s['scope']} setting)",
                             read_only=s["name"] == "rule", choices=list(s["choices"]),
                             setting=s["name"], range_text=text))
    return out


def all_parameters() -> List[Parameter]:
    return _node_parameters() + _setting_parameters()


def semantic_config(values: Dict[str, Any], parameters: List[Parameter]) -> "_core.SemanticConfig":
    """SemanticConfig of the settings' current values (unchecked)."""
    config = _core.SemanticConfig()
    for p in parameters:
        if p.setting is not None and p.name in values:
            setattr(config, p.setting, values[p.name])
    return config


def coerce(p: Parameter, value):
    """(value in the parameter's type, "") or (None, why not): an integer is taken for a
    floating-point parameter (`-p length_scale:=1`, `ds_multiplier: 2` in YAML), nothing else
    changes type."""
    kind = type(p.default)
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value), ""
    if not isinstance(value, kind) or (kind is int and isinstance(value, bool)):
        return None, (f"{p.name} must be a {kind.__name__}, got {value!r} "
                      f"({type(value).__name__})")
    return value, ""


def problem(values: Dict[str, Any], parameters: List[Parameter]) -> str:
    """Why these values cannot be used together ('' when they can): the node's checks, then the
    core's validation of the settings, the kernel bound at the resolution and the sensor model."""
    for p in parameters:
        if p.name not in values:
            continue
        v = values[p.name]
        if p.choices and v not in p.choices:
            return f"{p.name} = '{v}' must be one of {', '.join(p.choices)}"
        if p.check is not None and not p.check[0](v):
            return f"{p.name} = {v} must be {p.check[1]}"
    config = semantic_config(values, parameters)
    text = _core.config_problem(config)
    if text:
        return _ros_names(text, parameters)
    text = _core.support_problem(config, values.get("resolution", 0.2))
    if text:
        return text
    return _core.sensor_model_problem(values["sensor_model.hit"], values["sensor_model.miss"],
                                      values["sensor_model.min"], values["sensor_model.max"])


def _ros_names(text: str, parameters: List[Parameter]) -> str:
    """The core names a setting by its field (max_range); say the parameter's name."""
    for p in parameters:
        if p.setting is not None and p.setting != p.name and text.startswith(p.setting + " "):
            return p.name + text[len(p.setting):]
    return text

