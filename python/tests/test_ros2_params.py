"""The ROS 2 node's parameters without ROS: every setting of the core's list is a parameter with
its ROS 1 name (dots for slashes) and the core's default, the checks refuse what the core
refuses with the core's words, and the ROS 2 live profile holds config/mapping_live.yaml's
values."""
import math

import pytest

yaml = pytest.importorskip("yaml", reason="PyYAML (the ROS 2 wheels bring it)")

from evidential_octomap import _core  # noqa: E402
from evidential_octomap.ros2 import parameters  # noqa: E402
from conftest import REPO  # noqa: E402

PARAMS = parameters.all_parameters()


def defaults():
    return {p.name: p.default for p in PARAMS}


def test_every_setting_is_a_parameter_with_its_ros_name_and_the_cores_default():
    by_name = {p.name: p for p in PARAMS}
    config = _core.SemanticConfig()
    for s in _core.settings():
        p = by_name[s["ros_name"].replace("/", ".")]
        assert p.setting == s["name"] and p.default == getattr(config, s["name"])
    assert len(by_name) == len(PARAMS)  # no name twice


def test_the_defaults_are_accepted():
    assert parameters.problem(defaults(), PARAMS) == ""


@pytest.mark.parametrize("name, value, reason", [
    ("length_scale", -1.0, "length_scale = -1 must be finite and > 0"),
    ("sensor_model.max_range", math.nan, "sensor_model.max_range = nan must be"),
    ("rule", "bayes", "rule = 'bayes' must be one of dempster, sbki, ebs"),
    ("insert_queue_size", 0, "insert_queue_size = 0 must be >= 1"),
    ("sensor_model.hit", 1.0, "sensor model: hit = 1 must lie in [0.5, 0.999]"),
    ("length_scale", 5.0, "kernel support up to 13.5914 m"),
])
def test_a_bad_value_is_refused_with_its_reason(name, value, reason):
    values = defaults()
    values[name] = value
    assert parameters.problem(values, PARAMS).startswith(reason)


def test_the_ros2_live_profile_holds_the_ros1_live_profile():
    ros1 = yaml.safe_load((REPO / "config" / "mapping_live.yaml").read_text())
    ros2 = yaml.safe_load((REPO / "config" / "ros2" / "mapping_live.yaml").read_text())
    values = ros2["/**"]["ros__parameters"]
    ros1.pop("settings_profile")
    assert values == {parameters.ros2_name(k): v for k, v in ros1.items()}
    names = {p.name for p in PARAMS}
    assert set(values) <= names
