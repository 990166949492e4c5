"""The Foxglove view: a WebSocket client on 127.0.0.1 receives the map as a SceneUpdate with one
cube per occupied voxel in its class colour; the vectorised encoder writes the SDK's bytes; a bag
mapped with the view writes the same views to an MCAP."""
import asyncio
import json
import struct

import numpy as np
import pytest

pytest.importorskip("foxglove", reason="the bags extra: pip install '.[bags]'")
websockets = pytest.importorskip("websockets", reason="the test extra: pip install '.[test]'")

import evidential_octomap as eo  # noqa: E402
from evidential_octomap.foxglove_view import (FoxgloveView, encode_cubes,  # noqa: E402
                                              encode_scene_update, ramp, voxel_colors)
from foxglove import messages as fm  # noqa: E402
from conftest import wall  # noqa: E402


def fields(buf):
    """(field number, value) of a protobuf message: bytes for length-delimited fields, float
    for fixed64 (doubles), int for varints."""
    i, out = 0, []
    while i < len(buf):
        key, i = _varint(buf, i)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, i = _varint(buf, i)
        elif wire == 1:
            value, i = struct.unpack_from("<d", buf, i)[0], i + 8
        elif wire == 2:
            n, i = _varint(buf, i)
            value, i = buf[i:i + n], i + n
        else:
            raise ValueError(f"wire type {wire}")
        out.append((number, value))
    return out


def _varint(buf, i):
    shift = value = 0
    while True:
        b = buf[i]
        i += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            return value, i


def first_class_scene(port):
    """The payload of the first /map/voxels/class message a Foxglove client (WebSocket,
    foxglove.sdk.v1) gets from the server on `port`."""
    async def receive():
        async with websockets.connect(f"ws://127.0.0.1:{port}", max_size=None,
                                      subprotocols=["foxglove.sdk.v1"]) as ws:
            channels = {}
            while "/map/voxels/class" not in channels:
                msg = json.loads(await asyncio.wait_for(ws.recv(), 20))
                if msg["op"] == "advertise":
                    channels.update({c["topic"]: c["id"] for c in msg["channels"]})
            await ws.send(json.dumps({"op": "subscribe", "subscriptions": [
                {"id": 3, "channelId": channels["/map/voxels/class"]}]}))
            while True:
                data = await asyncio.wait_for(ws.recv(), 20)
                if isinstance(data, bytes) and data[0] == 1:
                    return data[13:]

    return asyncio.run(receive())


def cubes_of(scene_update: bytes):
    """[(centre, size, rgba)] of every cube of every entity (SceneUpdate.entities = 2,
    SceneEntity.cubes = 8; CubePrimitive pose 1 / size 2 / color 3)."""
    cubes = []
    for number, entity in fields(scene_update):
        assert number == 2
        for n, cube in fields(entity):
            if n != 8:
                continue
            c = dict(fields(cube))
            position = dict(fields(dict(fields(c[1]))[1]))
            size = dict(fields(c[2]))
            color = dict(fields(c[3]))
            cubes.append(((position.get(1, 0.0), position.get(2, 0.0), position.get(3, 0.0)),
                          size.get(1, 0.0), tuple(color.get(k, 0.0) for k in (1, 2, 3, 4))))
    return cubes


@pytest.fixture
def wall_map():
    classes = eo.bundled_class_table("semantickitti")
    points, evidence = wall(label=9, num_classes=20)
    tree = eo.EvidentialOcTree(0.2, classes)
    tree.insert_scan(points, evidence, origin=(0, 0, 0))
    return tree, classes


def test_the_uncertainty_view_shows_the_probability_that_the_label_is_wrong(wall_map):
    tree, classes = wall_map
    leaves = tree.leaves(occupied_only=True)
    colours = voxel_colors(leaves, classes, "uncertainty")[:, :3]
    np.testing.assert_allclose(colours, ramp(leaves.error_probability))
    assert not np.allclose(colours, ramp(leaves.uncertainty))  # not the vacuity u


def test_the_vectorised_encoder_writes_the_sdks_own_scene_update_bytes():
    centers = np.array([[1.5, 2.5, 3.5], [4.1, -5.2, 6.3]])
    sizes = np.array([0.2, 0.4])
    rgba = np.array([[0.1, 0.2, 0.3, 1.0], [0.5, 0.6, 0.7, 1.0]])
    ours = encode_scene_update("map", "voxels", 1_200_000_000, encode_cubes(centers, sizes, rgba),
                               {"view": "class"})
    sdk = fm.SceneUpdate(entities=[fm.SceneEntity(
        timestamp=fm.Timestamp(sec=1, nsec=200_000_000), frame_id="map", id="voxels",
        metadata=[fm.KeyValuePair(key="view", value="class")],
        cubes=[fm.CubePrimitive(
            pose=fm.Pose(position=fm.Vector3(x=float(c[0]), y=float(c[1]), z=float(c[2])),
                         orientation=fm.Quaternion(x=0, y=0, z=0, w=1)),
            size=fm.Vector3(x=float(s), y=float(s), z=float(s)),
            color=fm.Color(r=q[0], g=q[1], b=q[2], a=q[3])) for c, s, q in zip(centers, sizes, rgba)])])
    assert ours == sdk.encode()


async def receive_scene(view, tree, topic):
    """Connects like Foxglove (subprotocol foxglove.sdk.v1), subscribes to `topic`, publishes the
    map and returns the first message data on the subscription."""
    async with websockets.connect(f"ws://127.0.0.1:{view.port}",
                                  subprotocols=["foxglove.sdk.v1"], max_size=None) as ws:
        channels = {}
        while topic not in channels:
            msg = json.loads(await asyncio.wait_for(ws.recv(), 10))
            if msg["op"] == "advertise":
                channels.update({c["topic"]: c for c in msg["channels"]})
        assert channels[topic]["schemaName"] == "foxglove.SceneUpdate"
        assert view.publish(tree) == 0  # nobody subscribed: nothing computed, nothing sent
        await ws.send(json.dumps({"op": "subscribe",
                                  "subscriptions": [{"id": 7, "channelId": channels[topic]["id"]}]}))
        await asyncio.sleep(0.3)  # the server registers the subscription
        view.publish(tree)
        while True:
            data = await asyncio.wait_for(ws.recv(), 10)
            if isinstance(data, bytes) and data[0] == 1:  # message data
                sub, = struct.unpack_from("<I", data, 1)
                assert sub == 7
                return data[1 + 4 + 8:]


def test_a_websocket_client_receives_one_cube_per_occupied_voxel_in_its_class_colour(wall_map):
    tree, classes = wall_map
    view = FoxgloveView(classes, frame="map", port=0)  # a free loopback port
    try:
        assert view.port > 0
        payload = asyncio.run(receive_scene(view, tree, "/map/voxels/class"))
    finally:
        view.close()
    leaves = tree.leaves(occupied_only=True)
    cubes = cubes_of(payload)
    assert len(cubes) == len(leaves.sizes) > 0
    road = tuple(np.asarray(classes.colors[9], dtype=float) / 255) + (1.0,)
    assert {c[2] for c in cubes} == {road}
    centres = np.array(sorted(c[0] for c in cubes))
    np.testing.assert_allclose(centres, np.array(sorted(map(tuple, leaves.centers))), atol=1e-6)
    np.testing.assert_allclose([c[1] for c in cubes], 0.2, rtol=1e-6)


def test_a_bag_mapped_with_the_view_writes_the_views_to_an_mcap(tmp_path, wall_map):
    tree, classes = wall_map
    path = tmp_path / "views.mcap"
    view = FoxgloveView(classes, serve=False, mcap=str(path), period=0.0)
    points, evidence = wall(label=9, num_classes=20)
    view.update(tree, points, np.eye(4), 5_000_000_000, sensor_frame="velodyne",
                evidence=evidence)
    view.finish(tree)
    view.close()
    data = path.read_bytes()
    assert data[:8] == b"\x89MCAP0\r\n" and view.published == 2
    for topic in (b"/map/voxels/class", b"/map/voxels/uncertainty", b"/map/voxels/conflict",
                  b"/map/cloud", b"/tf"):
        assert topic in data
    assert view.last_voxels == len(tree.leaves(occupied_only=True).sizes)


def test_the_command_line_serves_the_map_it_builds_to_a_foxglove_client(tmp_path):
    """`bag map --foxglove` on a ROS 2 MCAP bag written by `bag write`: a client connecting
    while the command runs receives the map.ot's occupied voxels as cubes."""
    import subprocess
    import sys
    from conftest import KITTI, REPO
    from evidential_octomap import bag
    classes_path = REPO / "config" / "classes_semantickitti.yaml"
    classes = eo.ClassTable.load(str(classes_path))
    bag.write_bag(KITTI, tmp_path / "one", classes, bag.WriteOptions(scans=1))
    proc = subprocess.Popen(
        [sys.executable, "-m", "evidential_octomap.bag", "map", str(tmp_path / "one"),
         "--classes", str(classes_path), "--out", str(tmp_path / "out"), "--topic",
         "/velodyne_points/evidence", "--no-render", "-q", "--foxglove", "--port", "0",
         "--keep-serving", "30", "--view-period", "1"],
        stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stderr.readline()
        assert line.startswith("foxglove: open ws://127.0.0.1:"), line
        port = int(line.split("ws://127.0.0.1:")[1].split()[0])

        cubes = cubes_of(first_class_scene(port))
        # The served map is the one written, once the command has written it.
        for _ in range(100):
            if (tmp_path / "out" / "summary.json").is_file():
                break
            asyncio.run(asyncio.sleep(0.1))
        tree = eo.load(tmp_path / "out" / "map.ot")
        # One scan: every publication (after it, at the end, while serving) is the whole map.
        assert len(cubes) == len(tree.leaves(occupied_only=True).sizes) > 0
    finally:
        proc.terminate()
        proc.wait(10)
