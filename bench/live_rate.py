#!/usr/bin/python3
"""The live node fed by the player at a fixed rate: does it keep up at steady state?

    bench/live_rate.py --minutes 5 --rate 10 --out build/live_rate [--max-range 50]

Starts its own roscore (a free port), `roslaunch evidential_octomap mapping.launch` (the live
settings; max range 50 m as in docs/experiments/benchmarks.md, written to OUT/max_range.yaml and passed as
the launch's config:=, since config/mapping.yaml leaves the range unlimited) and `play_semantickitti.py` looping the bundled scans (0..9, 0..9, ...: the area
revisited) with `_rate:=RATE` (RATE clouds a second, as long as the player keeps up: the rate
received is measured, from ~status). Every
5 s the node's ~status goes to samples.csv; summary.json gives, after the first minute (steady
state), the clouds received and inserted per second, the drops, the queue length and the insert
times, and per stage (from the ~status sent after every insert): reading the cloud (reception
thread), the insert's wait for the map lock, the insert, and the publish pass with the part of it
that holds the map lock. `--views` subscribes to the markers and the voxel cloud as rviz does, so
the views are built at ~publish_rate while the node maps. Needs the sourced catkin workspace;
outside CI (a measurement, not a test).
"""
import argparse
import csv
import importlib.util
import json
import os
import subprocess
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_spec = importlib.util.spec_from_file_location(
    "soak_node", os.path.join(REPO, "test/reliability/soak_node.py"))
soak_node = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(soak_node)  # start_roscore(), stop()

FIELDS = ["t_s", "clouds_received", "clouds_inserted", "clouds_dropped_queue",
          "clouds_dropped_invalid", "clouds_dropped_tf", "queue_length", "last_insert_ms",
          "mean_insert_ms", "map_leaves"]


STAGES = ["last_read_ms", "last_lock_wait_ms", "last_insert_ms", "last_publish_ms",
          "last_publish_lock_ms"]
VIEW_TOPICS = ["/occupied_cells_vis_array", "/uncertainty_cells_vis_array", "/semantic_cloud"]


def percentiles(values):
    values = sorted(values)
    if not values:
        return {}
    pick = lambda q: values[min(len(values) - 1, int(q * len(values)))]
    return {"median": pick(0.5), "p95": pick(0.95), "max": values[-1], "n": len(values)}


def stage_summary(inserts, t_from):
    """Per stage over the inserts after t_from: each entry is one ~status after an insert."""
    window = [i for i in inserts if i["t"] >= t_from]
    out = {k: percentiles([i[k] for i in window]) for k in STAGES}
    if window:
        span = window[-1]["t"] - window[0]["t"]
        busy = sum(i["last_lock_wait_ms"] + i["last_insert_ms"] for i in window[1:]) / 1e3
        out["insertion_thread_busy_share"] = busy / span if span > 0 else None
        out["max_lock_wait_ms"] = window[-1]["max_lock_wait_ms"]
        out["max_publish_lock_ms"] = window[-1]["max_publish_lock_ms"]
    return out


def steady_summary(rows, warmup_s, rate):
    first = next(r for r in rows if r["t_s"] >= warmup_s)
    last = rows[-1]
    span = last["t_s"] - first["t_s"]
    delta = {k: last[k] - first[k] for k in FIELDS[1:6]}
    window = [r for r in rows if r["t_s"] >= warmup_s]
    return {"player_rate_param": rate, "steady_from_s": first["t_s"], "steady_span_s": span,
            "received_per_s": delta["clouds_received"] / span,
            "inserted_per_s": delta["clouds_inserted"] / span,
            "dropped_queue": delta["clouds_dropped_queue"],
            "dropped_invalid": delta["clouds_dropped_invalid"],
            "dropped_tf": delta["clouds_dropped_tf"],
            "queue_length_max": max(r["queue_length"] for r in window),
            "last_insert_ms_median": sorted(r["last_insert_ms"] for r in window)[len(window) // 2],
            "last_insert_ms_max": max(r["last_insert_ms"] for r in window),
            "mean_insert_ms_end": last["mean_insert_ms"],
            "load_average_end": open("/proc/loadavg").read().split()[:3]}


def run(args):
    os.makedirs(args.out, exist_ok=True)
    procs = [soak_node.start_roscore()]
    try:
        time.sleep(3)
        import rospy
        from evidential_octomap.msg import MappingStatus
        log = open(os.path.join(args.out, "ros.log"), "w")
        config = os.path.join(os.path.abspath(args.out), "max_range.yaml")
        with open(config, "w") as f:
            f.write("sensor_model:\n  max_range: %g\n" % args.max_range)
        procs.append(subprocess.Popen(["roslaunch", "evidential_octomap", "mapping.launch",
                                       "cloud_in:=/velodyne_points", "config:=" + config],
                                      stdout=log,
                                      stderr=subprocess.STDOUT))
        procs.append(subprocess.Popen(["rosrun", "evidential_octomap", "play_semantickitti.py",
                                       "_rate:=%g" % args.rate, "_loop:=true",
                                       "__name:=player", "velodyne_points:=/velodyne_points"],
                                      stdout=log, stderr=subprocess.STDOUT))
        rospy.init_node("live_rate", disable_signals=True)
        status, inserts = {}, []

        def on_status(m):
            last = status.get("msg")
            if last is not None and m.clouds_inserted > last.clouds_inserted:
                entry = {k: getattr(m, k) for k in STAGES + ["max_lock_wait_ms",
                                                             "max_publish_lock_ms"]}
                entry["t"] = time.time()
                inserts.append(entry)
            status["msg"] = m

        rospy.Subscriber("/evidential_mapping_node/status", MappingStatus, on_status,
                         queue_size=50)
        if args.views:
            from sensor_msgs.msg import PointCloud2
            from visualization_msgs.msg import MarkerArray
            for topic in VIEW_TOPICS:
                kind = PointCloud2 if topic.endswith("cloud") else MarkerArray
                rospy.Subscriber(topic, kind, lambda m: None, queue_size=1)
        while "msg" not in status or status["msg"].clouds_received == 0:
            time.sleep(0.1)
        t0 = time.time()
        load_start = open("/proc/loadavg").read().split()[:3]
        rows = []
        with open(os.path.join(args.out, "samples.csv"), "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=FIELDS)
            writer.writeheader()
            while time.time() < t0 + 60.0 * args.minutes:
                time.sleep(5.0)
                s = status["msg"]
                row = {k: getattr(s, k) for k in FIELDS[1:]}
                row["t_s"] = round(time.time() - t0, 1)
                rows.append(row)
                writer.writerow(row)
                f.flush()
        summary = steady_summary(rows, 60.0, args.rate)
        summary["stages"] = stage_summary(inserts, t0 + 60.0)
        summary["views_subscribed"] = bool(args.views)
        summary["load_average_start"] = load_start
        summary["minutes"] = args.minutes
        summary["max_range_m"] = args.max_range
        with open(os.path.join(args.out, "summary.json"), "w") as f:
            json.dump(summary, f, indent=2)
        print(json.dumps(summary, indent=2))
    finally:
        soak_node.stop(procs)


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--minutes", type=float, default=5.0)
    p.add_argument("--rate", type=float, default=20.0, help="the player's ~rate")
    p.add_argument("--out", default="build/live_rate")
    p.add_argument("--views", action="store_true",
                   help="subscribe to the markers and semantic_cloud as rviz does")
    p.add_argument("--max-range", type=float, default=50.0,
                   help="sensor_model/max_range [m] (< 0: unlimited, config/mapping.yaml's)")
    run(p.parse_args())


if __name__ == "__main__":
    main()
