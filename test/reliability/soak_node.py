#!/usr/bin/python3
"""Soak of evidential_mapping_node: hours of input compressed into minutes.

    python3 test/reliability/soak_node.py --minutes 30 --out build/soak [--autosave-period 10]
    python3 test/reliability/soak_node.py --plot build/soak/samples.csv docs/figures/soak.png
    python3 test/reliability/soak_node.py --plot build/on/samples.csv build/off/samples.csv on_off.png

Starts its own roscore (a free port) and the node (rosrun, from the sourced catkin workspace),
then replays a sequence (--data: by default the bundled scans, data/semantickitti_08_first10; one-hot
evidence from the hard predictions, as play_semantickitti.py) forth and back, 0..9, 8..0, 1..9, ...
(a long generated sequence: 0..519, 518..0, ...), with their poses,
as fast as the node sustains: the next scan is published as soon as fewer than two are waiting
(closed loop, so the node is never idle and the queue never overflows by design). Every 10 s the
node's ~status (clouds inserted, dropped, queue length, last / mean insert time, map leaves and
memory, autosave stall) and its RSS (/proc/<pid>/status VmRSS) are written to samples.csv; at the
end a summary to summary.json. --plot draws one or more CSVs (overlaid) to a PNG (matplotlib).
"""
import argparse
import csv
import importlib.util
import json
import os
import signal
import socket
import subprocess
import sys
import time

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def forth_and_back(n):
    """0..n-1, n-2..0, 1..n-1, ...: every step to a neighbouring scan (a revisit replay)."""
    i, step = 0, 1
    while True:
        yield i
        if not 0 <= i + step < n:
            step = -step
        i += step


def rss_mb(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def start_roscore():
    """A roscore on a free port of its own, with ROS_MASTER_URI pointing at it."""
    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    return subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)


def stop(procs):
    """Terminates the processes, the last started first (killed after 30 s)."""
    for p in reversed(procs):
        p.terminate()
        try:
            p.wait(30)
        except subprocess.TimeoutExpired:
            p.kill()


def soak(args):
    os.makedirs(args.out, exist_ok=True)
    port = free_port()
    os.environ["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    roscore = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    node = None
    try:
        import rospy
        from tf2_msgs.msg import TFMessage
        from sensor_msgs.msg import PointCloud2
        from std_msgs.msg import Header
        from evidential_octomap.msg import MappingStatus
        import numpy as np

        spec = importlib.util.spec_from_file_location(
            "player", os.path.join(REPO, "src/ros/scripts/play_semantickitti.py"))
        player = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(player)

        time.sleep(3)
        rospy.init_node("soak_node", disable_signals=True)
        node_args = ["rosrun", "evidential_octomap", "evidential_mapping_node",
                     "cloud_in:=/velodyne_points", "_insert_queue_size:=2",
                     "_autosave_period:=%g" % args.autosave_period,
                     "_autosave_path:=%s" % os.path.join(args.out, "autosave.ot"),
                     "_classes:=%s" % os.path.abspath(args.classes)]
        node_args += args.node_param
        log = open(os.path.join(args.out, "node.log"), "w")
        node_env = dict(os.environ)
        node_env.update(v.split("=", 1) for v in args.node_env)
        node = subprocess.Popen(node_args, stdout=log, stderr=subprocess.STDOUT, env=node_env)

        reader = player.DatasetReader(args.data, args.classes, "predictions")
        names = player.load_class_table(args.classes)[0]

        def cloud_and_pose(i):  # read when published: a long sequence does not fit in memory
            _, xyz, _, cls, pose = reader.load(i)
            evidence = np.zeros((len(cls), len(names)), dtype=np.float32)
            evidence[np.arange(len(cls)), cls] = 20.0
            return player.make_cloud(xyz, evidence, Header(frame_id="velodyne")), pose
        cache = [cloud_and_pose(i) for i in range(len(reader))] if len(reader) <= 50 else None

        status = {"msg": None}
        rospy.Subscriber("/evidential_mapping_node/status", MappingStatus,
                         lambda m: status.__setitem__("msg", m), queue_size=10)
        cloud_pub = rospy.Publisher("/velodyne_points", PointCloud2, queue_size=2)
        tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=10)
        deadline = time.time() + 60
        while (cloud_pub.get_num_connections() == 0 or tf_pub.get_num_connections() == 0 or
               status["msg"] is None) and time.time() < deadline:
            time.sleep(0.1)
        time.sleep(0.5)

        order = forth_and_back(len(reader))
        published = 0
        t0 = time.time()
        end = t0 + 60.0 * args.minutes
        next_sample = t0
        fields = ["t_s", "published", "inserted", "dropped_queue", "dropped_invalid", "dropped_tf",
                  "queue_length", "last_insert_ms", "mean_insert_ms", "map_leaves",
                  "map_semantic_leaves", "map_memory_mb", "rss_mb", "autosaves_written",
                  "autosaves_failed", "last_autosave_stall_ms", "max_autosave_stall_ms",
                  "local_map_tiles_on_disk"]
        samples = open(os.path.join(args.out, "samples.csv"), "w", newline="")
        writer = csv.writer(samples)
        writer.writerow(fields)
        insert_ms_window = []
        last_inserted = 0
        while time.time() < end:
            s = status["msg"]
            done = (s.clouds_inserted + s.clouds_dropped_queue + s.clouds_dropped_invalid +
                    s.clouds_dropped_tf) if s else 0
            if s and s.clouds_inserted != last_inserted:
                insert_ms_window.append(s.last_insert_ms)
                last_inserted = s.clouds_inserted
            if published - done < 2:
                i = next(order)
                cloud, pose = cache[i] if cache else cloud_and_pose(i)
                stamp = rospy.Time.now()
                tf_pub.publish(TFMessage([player.make_tf(pose, stamp, "map", "velodyne")]))
                time.sleep(0.02)  # TF first, as the player does
                cloud.header.stamp = stamp
                cloud_pub.publish(cloud)
                published += 1
            else:
                time.sleep(0.005)
            if time.time() >= next_sample and s is not None:
                writer.writerow([round(time.time() - t0, 1), published, s.clouds_inserted,
                                 s.clouds_dropped_queue, s.clouds_dropped_invalid,
                                 s.clouds_dropped_tf, s.queue_length, round(s.last_insert_ms, 1),
                                 round(s.mean_insert_ms, 1), s.map_leaves, s.map_semantic_leaves,
                                 round(s.map_memory_bytes / 1e6, 2), round(rss_mb(node.pid), 1),
                                 s.autosaves_written, s.autosaves_failed,
                                 round(s.last_autosave_stall_ms, 1),
                                 round(s.max_autosave_stall_ms, 1), s.local_map_tiles_on_disk])
                samples.flush()
                next_sample += args.sample_s
        samples.close()
        s = status["msg"]
        summary = {"minutes": args.minutes, "published": published,
                   "inserted": s.clouds_inserted, "dropped_queue": s.clouds_dropped_queue,
                   "dropped_invalid": s.clouds_dropped_invalid, "dropped_tf": s.clouds_dropped_tf,
                   "mean_insert_ms": s.mean_insert_ms, "rss_mb_end": rss_mb(node.pid),
                   "map_leaves": s.map_leaves, "map_memory_mb": s.map_memory_bytes / 1e6,
                   "autosaves_written": s.autosaves_written, "autosaves_failed": s.autosaves_failed,
                   "max_autosave_stall_ms": s.max_autosave_stall_ms,
                   "scans_per_s": s.clouds_inserted / (time.time() - t0),
                   "node_alive": node.poll() is None}
        with open(os.path.join(args.out, "summary.json"), "w") as f:
            json.dump(summary, f, indent=2)
        print(json.dumps(summary, indent=2))
    finally:
        if node is not None:
            # SIGINT, as roslaunch stops a node: its clean shutdown (the last autosave; under
            # ASan, the leak check) runs; SIGTERM would end it without.
            node.send_signal(signal.SIGINT)
            try:
                node.wait(120)
            except subprocess.TimeoutExpired:
                node.kill()
        roscore.terminate()
        roscore.wait()


def plot(csv_paths, png_path):
    """One figure; several CSVs (e.g. bounded memory on and off) overlaid, each named by its
    directory."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    for n, path in enumerate(csv_paths):
        rows = list(csv.DictReader(open(path)))
        t = [float(r["t_s"]) / 60.0 for r in rows]
        col = lambda k: [float(r[k]) for r in rows]  # noqa: E731
        run = os.path.basename(os.path.dirname(os.path.abspath(path)))
        tag = (run + ": ") if len(csv_paths) > 1 else ""
        colour = "C%d" % n
        ax[0].plot(t, col("rss_mb"), color=colour, label=tag + "node RSS")
        ax[0].plot(t, col("map_memory_mb"), "--", color=colour, label=tag + "map memoryUsage()")
        ax[1].plot(t, col("last_insert_ms"), ".", ms=3, color=colour, label=tag + "last insert")
        ax[1].plot(t, col("mean_insert_ms"), color=colour, label=tag + "mean insert")
        drops = [a + b + c for a, b, c in zip(col("dropped_queue"), col("dropped_invalid"),
                                              col("dropped_tf"))]
        ax[2].plot(t, col("queue_length"), ".", ms=3, color=colour, label=tag + "queue length")
        ax[2].plot(t, drops, color=colour, label=tag + "clouds dropped (total)")
        ax[3].plot(t, col("map_leaves"), color=colour, label=tag + "map leaves (in memory)")
        ax[3].plot(t, col("inserted"), ":", color=colour, label=tag + "scans inserted")
    for a, unit in zip(ax, ("MB", "insert [ms]", "clouds", "count")):
        a.set_ylabel(unit)
        a.legend(loc="upper left", fontsize=7)
    ax[3].set_yscale("log")
    ax[3].set_xlabel("minutes")
    runs = ", ".join(os.path.basename(os.path.dirname(os.path.abspath(p))) for p in csv_paths)
    fig.suptitle("evidential_mapping_node soak (%s): forth and back, closed loop" % runs)
    fig.tight_layout()
    fig.savefig(png_path, dpi=90)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--minutes", type=float, default=30.0)
    p.add_argument("--out", default=os.path.join(REPO, "build/soak"))
    p.add_argument("--data", default=os.path.join(REPO, "data/semantickitti_08_first10"),
                   help="a SemanticKITTI-layout sequence (e.g. one of evidential_octomap generate)")
    p.add_argument("--classes", default=os.path.join(REPO, "config/classes_semantickitti.yaml"))
    p.add_argument("--sample-s", type=float, default=10.0)
    p.add_argument("--autosave-period", type=float, default=10.0)
    p.add_argument("--node-param", action="append", default=[],
                   help="extra _name:=value for the node, e.g. _local_map/radius:=60")
    p.add_argument("--node-env", action="append", default=[], metavar="NAME=VALUE",
                   help="set in the node's environment only, e.g. LD_LIBRARY_PATH of a "
                        "sanitized workspace")
    p.add_argument("--plot", nargs="+", metavar="CSV... PNG",
                   help="plot samples.csv files (overlaid) into PNG")
    args = p.parse_args()
    if args.plot:
        if len(args.plot) < 2:
            p.error("--plot needs at least one CSV and the PNG")
        plot(args.plot[:-1], args.plot[-1])
        return 0
    soak(args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
