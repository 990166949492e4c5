"""The ROS 2 node with real ROS 2 processes: the node in its own process, a publisher process
replaying the bundled scans with TF (python -m evidential_octomap.ros2.replay), and this test
process as the client (services, parameters, late subscribers, queries), on a DDS domain of its
own. The map equals the Python API's and the CLI's map of the same scans; malformed clouds,
missing TF and bad parameters leave the node up with a clear status."""
import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy", reason="the ROS 2 wheels: pip install '.[ros2]'")
for interfaces in ("tf2_msgs", "evidential_octomap_msgs"):
    pytest.importorskip(interfaces, reason=f"{interfaces}: pip install "
                        f"./python/ros2_interfaces/{interfaces}")

import evidential_octomap as eo  # noqa: E402
from evidential_octomap.ros2.node import LATCHED, MARKER_TOPICS, MappingNode  # noqa: E402
from nav_msgs.msg import OccupancyGrid  # noqa: E402
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue  # noqa: E402
from rcl_interfaces.srv import SetParameters  # noqa: E402
from sensor_msgs.msg import PointCloud2  # noqa: E402
from std_msgs.msg import String  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402
from evidential_octomap_msgs.srv import QueryMap, SaveMap  # noqa: E402
from geometry_msgs.msg import Point  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

from conftest import KITTI, REPO  # noqa: E402
from test_kitti import cli_binary  # noqa: E402

NODE = "/evidential_mapping_node"
SCANS = 3  # mapped; a 4th cloud has no TF, and a malformed cloud comes first
DOMAIN = str(100 + os.getpid() % 100)  # a DDS domain of this run only


def env():
    return dict(os.environ, ROS_DOMAIN_ID=DOMAIN)


@pytest.fixture(scope="module")
def node(tmp_path_factory):
    out = tmp_path_factory.mktemp("ros2")
    log = open(out / "node.log", "w")
    process = subprocess.Popen(
        [sys.executable, "-m", "evidential_octomap.ros2", "--ros-args",
         "-r", "cloud_in:=/velodyne_points/evidence", "-p", "cloud_in_qos:=reliable",
         "-p", "publish_rate:=2.0", "-p", f"save_path:={out / 'saved' / 'map.ot'}",
         "-p", "autosave_period:=1.0", "-p", f"autosave_path:={out / 'autosave.ot'}",
         "-p", "transform_timeout:=0.3", "-p", "foxglove_port:=0"], stdout=log,
        stderr=subprocess.STDOUT, env={k: v for k, v in env().items() if k != "OMP_WAIT_POLICY"})
    yield process, out
    process.terminate()
    try:
        process.wait(timeout=10)
    except subprocess.TimeoutExpired:
        process.kill()
    log.close()


@pytest.fixture(scope="module")
def client(node):
    os.environ["ROS_DOMAIN_ID"] = DOMAIN
    rclpy.init()
    n = rclpy.create_node("evidential_octomap_test_client")
    n.statuses = []
    n.create_subscription(String, f"{NODE}/status", lambda m: n.statuses.append(
        json.loads(m.data)), LATCHED)
    yield n
    n.destroy_node()
    rclpy.shutdown()


def spin_until(n, predicate, timeout=30.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        rclpy.spin_once(n, timeout_sec=0.05)
        if predicate():
            return True
    return False


def status(n, predicate=lambda s: True, timeout=30.0):
    assert spin_until(n, lambda: n.statuses and predicate(n.statuses[-1]), timeout), \
        n.statuses[-1:] or "no status"
    return n.statuses[-1]


def call(n, srv_type, name, request, timeout=30.0):
    c = n.create_client(srv_type, name)
    assert c.wait_for_service(timeout_sec=timeout), f"no service {name}"
    future = c.call_async(request)
    assert spin_until(n, future.done, timeout), f"{name} did not answer"
    n.destroy_client(c)
    return future.result()


def latched(n, msg_type, topic, timeout=30.0):
    got = []
    sub = n.create_subscription(msg_type, topic, got.append, LATCHED)
    assert spin_until(n, lambda: got, timeout), f"nothing on {topic}"
    n.destroy_subscription(sub)
    return got[-1]


@pytest.fixture(scope="module")
def replayed(node, client):
    """A malformed cloud, SCANS scans with TF and one without, paced by the node's status."""
    run = subprocess.run(
        [sys.executable, "-m", "evidential_octomap.ros2.replay", str(KITTI), "--scans",
         str(SCANS + 1), "--no-tf-after", str(SCANS), "--malformed-first", "--paced"],
        capture_output=True, text=True, env=env(), timeout=120)
    assert run.returncode == 0, run.stderr
    return status(client, lambda s: s["clouds_inserted"] + s["clouds_dropped"] == SCANS + 2)


@pytest.fixture(scope="module")
def saved(replayed, client, node):
    path = node[1] / "saved" / "run1.ot"
    response = call(client, SaveMap, f"{NODE}/save_map", SaveMap.Request(path=str(path)))
    assert response.success, response.message
    assert response.path == str(path)
    return path.parent


def test_a_malformed_cloud_and_a_missing_transform_are_dropped_with_their_reason(replayed,
                                                                                node):
    s = replayed
    assert s["clouds_received"] == SCANS + 2 and s["clouds_inserted"] == SCANS
    assert s["dropped_by_reason"] == {"malformed": 1, "no_transform": 1}
    assert node[0].poll() is None  # still up
    assert "after the last transform 'map' -> 'base_link'" in s["last_drop"]["reason"]
    log = (node[1] / "node.log").read_text()
    assert "field 'evidence' has count 2, expected C = 20 (num_classes); map unchanged" in log


def test_network_evidence_without_a_calibration_file_gets_one_note(replayed, node):
    log = (node[1] / "node.log").read_text()
    assert log.count("the map's error probability is uncalibrated") == 1, log[-2000:]


def test_save_map_writes_the_ot_and_the_bt(saved, replayed, client, node):
    tree = eo.load(saved / "run1.ot")
    assert tree.num_leaves == replayed["map"]["leaves"]
    assert (saved / "run1.bt").read_bytes().startswith(b"# Octomap OcTree binary file")
    response = call(client, SaveMap, f"{NODE}/save_map", SaveMap.Request(path=""))  # save_path
    assert response.success and (node[1] / "saved" / "map.ot").is_file(), response.message


def test_the_map_equals_the_python_api_and_the_cli_maps_of_the_same_scans(saved, tmp_path,
                                                                          kitti_classes):
    """Labels at 20k points of the scans; the node's poses went through TF (quaternions), so a
    few points may fall in other voxels than with the dataset's 3 x 4 matrices."""
    dataset = eo.Dataset.open(str(KITTI), kitti_classes)
    reference = eo.EvidentialOcTree(0.2, kitti_classes)
    points = []
    for i in range(SCANS):
        scan = dataset.load(i)
        reference.insert_scan(scan.points_world(), eo.derive_evidence(scan, 20),
                              origin=scan.origin)
        points.append(scan.points_world())
    points = np.concatenate(points)[np.random.default_rng(0).choice(
        sum(len(p) for p in points), 20_000, replace=False)]
    labels = eo.load(saved / "run1.ot").query(points).labels
    maps = {"python": reference}
    if cli_binary() is not None:
        subprocess.run([str(cli_binary()), "map", "--data", str(KITTI), "--classes",
                        str(REPO / "config" / "classes_semantickitti.yaml"), "--out",
                        str(tmp_path), "--scans", str(SCANS), "--no-render", "-q",
                        "--no-calibration"], check=True, capture_output=True)
        maps["cli"] = eo.load(tmp_path / "map.ot")
    for name, tree in maps.items():
        agree = float(np.mean(tree.query(points).labels == labels))
        print(f"labels equal to the {name} map at {agree:.2%} of {len(points)} points")
        assert agree >= 0.999, (name, agree)


def test_a_late_subscriber_gets_the_latched_views(saved, client):
    occupied = eo.load(saved / "run1.ot").leaves(occupied_only=True)
    cloud = latched(client, PointCloud2, "/semantic_cloud")
    assert cloud.width == len(occupied.sizes)
    assert [f.name for f in cloud.fields] == ["x", "y", "z", "label", "uncertainty", "rgb",
                                              "conflict", "error_probability"]
    grid = latched(client, OccupancyGrid, "/projected_map")
    data = np.asarray(grid.data, dtype=np.int8)
    assert grid.info.width * grid.info.height == len(data) and (data == 100).any()
    markers = latched(client, MarkerArray, "/" + MARKER_TOPICS["class"])
    cubes = sum(len(m.points) for m in markers.markers)
    assert cubes == len(occupied.sizes)
    names = {name for name, _ in client.get_topic_names_and_types()}
    assert {"/" + t for t in MARKER_TOPICS.values()} <= names


def test_every_topic_of_the_rviz2_config_is_one_the_node_has(replayed, client):
    config = (REPO / "rviz_cfg" / "ros2_mapping.rviz").read_text().splitlines()
    named = {line.split(":", 1)[1].strip() for i, line in enumerate(config)
             if line.strip().startswith("Value: /")}
    assert len(named) == 5
    spin_until(client, lambda: False, 0.5)
    published = {name for name, _ in client.get_publisher_names_and_types_by_node(
        NODE.lstrip("/"), "/")}
    assert named <= published, named - published


def test_a_query_answers_the_labels_of_the_map(saved, client):
    points = np.array([[5.0, 0.0, -1.5], [0.0, 5.0, -1.5], [12.0, -3.0, -1.0],
                       [500.0, 0.0, 0.0]], np.float32)
    request = QueryMap.Request(points=[Point(x=float(x), y=float(y), z=float(z))
                                       for x, y, z in points])
    answer = call(client, QueryMap, f"{NODE}/query", request)
    expected = eo.load(saved / "run1.ot").query(points)
    np.testing.assert_array_equal(answer.labels, expected.labels)
    np.testing.assert_allclose(answer.error_probabilities, expected.error_probability)
    np.testing.assert_allclose(np.reshape(answer.beliefs, (4, -1)), expected.belief)
    assert answer.num_classes == 20 and (expected.labels[:3] >= 0).any()
    assert answer.labels[3] == -1 and answer.class_names[3] == "" and answer.occupancy[3] == -1
    names = eo.bundled_class_table("semantickitti").names
    assert all(n == (names[c] if c >= 0 else "") for n, c in zip(answer.class_names,
                                                                  answer.labels))


def test_foxglove_gets_the_live_map(saved, node):
    """foxglove_port: a Foxglove client (WebSocket, foxglove.sdk.v1) gets one cube per occupied
    leaf of the map the node saved."""
    pytest.importorskip("websockets", reason="the test extra")
    from test_bag_foxglove import cubes_of, first_class_scene
    log = (node[1] / "node.log").read_text()
    port = int(log.split("foxglove: open ws://127.0.0.1:")[1].split()[0])
    cubes = cubes_of(first_class_scene(port))
    assert len(cubes) == len(eo.load(saved / "run1.ot").leaves(occupied_only=True).sizes)


def set_parameter(client, name, value):
    p = Parameter(name=name, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                                  double_value=value))
    return call(client, SetParameters, f"{NODE}/set_parameters",
                SetParameters.Request(parameters=[p])).results[0]


def test_a_bad_parameter_is_refused_with_its_reason_and_a_good_one_applies(replayed, client,
                                                                          node):
    result = set_parameter(client, "length_scale", -1.0)
    assert not result.successful
    assert result.reason == "length_scale = -1 must be finite and > 0"
    result = set_parameter(client, "length_scale", 5.0)
    assert not result.successful and "kernel support up to" in result.reason
    result = set_parameter(client, "sensor_model.hit", 1.0)
    assert not result.successful and "hit = 1 must lie in [0.5, 0.999]" in result.reason
    assert set_parameter(client, "length_scale", 0.25).successful
    # Both events in one status: one published between the refusals and the set has only the
    # first.
    s = status(client, lambda s: "set length_scale=0.25" in s["events"])
    assert any("refused length_scale=-1.0" in e for e in s["events"]), s["events"]
    assert node[0].poll() is None


def test_the_autosave_holds_the_map(replayed, node):
    path = node[1] / "autosave.ot"
    end = time.monotonic() + 10
    while not path.is_file() and time.monotonic() < end:
        time.sleep(0.2)
    assert eo.load(path).num_leaves > 0


def test_at_10_hz_every_cloud_is_inserted_or_counted_as_dropped(saved, client, node):
    assert call(client, Trigger, f"{NODE}/reset", Trigger.Request()).success
    before = status(client, lambda s: s["map"]["leaves"] == 0)
    run = subprocess.run(
        [sys.executable, "-m", "evidential_octomap.ros2.replay", str(KITTI), "--rate", "10"],
        capture_output=True, text=True, env=env(), timeout=120)
    assert run.returncode == 0, run.stderr
    sent = json.loads(run.stdout.splitlines()[-1])["sent"]
    spin_until(client, lambda: False, 2.0)  # what is still on its way arrives
    s = status(client, lambda s: s["insert_queue"] == 0 and
               s["clouds_inserted"] + s["clouds_dropped"] == s["clouds_received"], 60)
    received = s["clouds_received"] - before["clouds_received"]
    inserted = s["clouds_inserted"] - before["clouds_inserted"]
    dropped = {k: n - before["dropped_by_reason"].get(k, 0)
               for k, n in s["dropped_by_reason"].items()
               if n > before["dropped_by_reason"].get(k, 0)}
    # What DDS delivered is accounted for cloud by cloud: inserted, or dropped with a reason
    # (a full queue, most of them, or a transform that came too late on a loaded machine).
    lost = s["clouds_lost_in_dds"] - before["clouds_lost_in_dds"]
    assert sent == 10 and received + lost <= sent
    assert inserted + sum(dropped.values()) == received and inserted >= 1
    assert set(dropped) <= {"queue_full", "no_transform"}, s["last_drop"]
    print(f"10 Hz: {received} of {sent} clouds received ({lost} reported lost in DDS), "
          f"{inserted} inserted, dropped {dropped}; median insert {s['insert_ms_median']} ms")


def test_the_node_runs_with_sleeping_openmp_threads(replayed, node):
    """launch/mapping.launch's OMP_WAIT_POLICY=passive, for the ROS 2 node too: the running
    process's environment has it (the fixture started it without)."""
    process, _ = node
    environ = open(f"/proc/{process.pid}/environ", "rb").read().split(b"\0")
    assert b"OMP_WAIT_POLICY=passive" in environ


def test_the_console_script_refuses_a_bad_parameter_at_start_up():
    script = os.path.join(os.path.dirname(sys.executable), "evidential_octomap_ros2")
    if not os.path.isfile(script):
        pytest.skip("the console script comes with pip install (not a source checkout)")
    run = subprocess.run([script, "--ros-args", "-p", "resolution:=-0.5"], capture_output=True,
                         text=True, env=env(), timeout=60)
    assert run.returncode == 1
    assert "parameter refused: resolution = -0.5 must be finite and > 0" in run.stderr


def test_the_views_thread_ends_when_the_context_shuts_down():
    """Ctrl-C or SIGTERM shuts the context down before the node stops its threads: the views
    thread then ends, rather than dying with a traceback at its next publisher call."""
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(DOMAIN) + 2)
    node = MappingNode(context=context, parameter_overrides=[
        rclpy.parameter.Parameter("autosave_period", value=0.0)])
    node.shutdown()  # its own threads stop; the loop below runs in this one
    node.running = True
    rclpy.shutdown(context=context)
    node._view_loop()  # returns


def test_raw_clouds_are_mapped_through_the_model_parameter(tmp_path):
    """`model`: a user's callable turns raw clouds (x, y, z, intensity) into evidence."""
    (tmp_path / "my_model.py").write_text(
        "import numpy as np\n"
        "def evidence(points, fields):\n"
        "    e = np.zeros((len(points), 20), np.float32)\n"
        "    e[:, 9] = 5.0 + 0 * fields['intensity']  # 'road' everywhere\n"
        "    return e\n")
    domain = str(int(DOMAIN) + 1)
    process = subprocess.Popen(
        [sys.executable, "-m", "evidential_octomap.ros2", "--ros-args", "-r",
         "cloud_in:=/velodyne_points", "-p", "cloud_in_qos:=reliable", "-p",
         f"model:={tmp_path / 'my_model.py'}:evidence", "-p", "autosave_period:=0.5", "-p",
         f"autosave_path:={tmp_path / 'raw.ot'}"], stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL, env=dict(env(), ROS_DOMAIN_ID=domain))
    try:
        run = subprocess.run(
            [sys.executable, "-m", "evidential_octomap.ros2.replay", str(KITTI), "--scans", "1",
             "--raw", "--topic", "/velodyne_points", "--paced"], capture_output=True, text=True,
            env=dict(env(), ROS_DOMAIN_ID=domain), timeout=120)
        assert run.returncode == 0, run.stderr
        end = time.monotonic() + 20
        while not (tmp_path / "raw.ot").is_file() and time.monotonic() < end:
            time.sleep(0.2)
        labels = eo.load(tmp_path / "raw.ot").leaves(occupied_only=True).labels
        assert set(np.unique(labels[labels >= 0])) == {9}
    finally:
        process.terminate()
        process.wait(timeout=10)
