#!/usr/bin/python3
"""What publishing costs as the map grows: the live node (mapping.launch, live profile) fed a
long sequence by the player, with rviz's topics subscribed, once publishing every view and the
whole map at publish_rate, once with the views bounded (~publish_radius) and the whole map at a
low rate (~full_map_period).

    bench/publish_cost.py --data DIR --out build/publish_cost [--rate 3] [--radius 20] [--period 30]

Per configuration: ~status sampled every 2 s (map leaves, last views / whole-map / publish pass
times, insert times) into <config>.csv; then summary.md (stamped) and publish_cost.png (views and
whole-map time against map size). Starts its own roscore; needs the sourced catkin workspace.
A measurement, not a test.
"""
import argparse
import csv
import datetime
import importlib.util
import os
import subprocess
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_spec = importlib.util.spec_from_file_location(
    "soak_node", os.path.join(REPO, "test/reliability/soak_node.py"))
soak_node = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(soak_node)  # start_roscore(), stop()

FIELDS = ["t_s", "clouds_received", "clouds_inserted", "clouds_dropped_queue", "map_leaves", "map_memory_bytes", "last_views_ms",
          "last_full_maps_ms", "last_publish_ms", "max_publish_ms", "last_insert_ms",
          "mean_insert_ms"]
TOPICS = {"occupied_cells_vis_array": "visualization_msgs/MarkerArray",
          "uncertainty_cells_vis_array": "visualization_msgs/MarkerArray",
          "evidential_map": "evidential_octomap/EvidentialMap",
          "projected_map": "nav_msgs/OccupancyGrid"}


def run_config(name, params, args, scans, status):
    """One node + player run on the running roscore; returns the ~status samples."""
    out = os.path.join(args.out, name)
    os.makedirs(out, exist_ok=True)
    config = os.path.join(out, "params.yaml")
    with open(config, "w") as f:
        f.write("".join("%s: %s\n" % kv for kv in params.items()))
    classes = os.path.join(args.data, "classes.yaml")
    log = open(os.path.join(out, "ros.log"), "w")
    load = open(os.path.join(out, "load.txt"), "w")
    load.write("start " + open("/proc/loadavg").read())
    status.clear()
    procs = [subprocess.Popen(["roslaunch", "evidential_octomap", "mapping.launch",
                               "config:=" + config, "classes:=" + classes],
                              stdout=log, stderr=subprocess.STDOUT)]
    try:
        while "msg" not in status:
            time.sleep(0.1)
        procs.append(subprocess.Popen(
            ["rosrun", "evidential_octomap", "play_semantickitti.py", "_data:=" + args.data,
             "_classes:=" + classes, "_rate:=%g" % args.rate, "_count:=%d" % scans, "_stay:=false",
             "__name:=player", "velodyne_points:=/velodyne_points"],
            stdout=log, stderr=subprocess.STDOUT))
        player, t0, rows, player_done = procs[-1], time.time(), [], None
        with open(os.path.join(args.out, name + ".csv"), "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=FIELDS)
            writer.writeheader()
            while time.time() < t0 + args.timeout_s:
                time.sleep(2.0)
                s = status["msg"]
                row = {k: getattr(s, k) for k in FIELDS[1:]}
                row["t_s"] = round(time.time() - t0, 1)
                rows.append(row)
                writer.writerow(row)
                if player_done is None and player.poll() is not None:
                    player_done = time.time()  # every scan sent: the queue drains, then stop
                if player_done and s.queue_length == 0 and time.time() - player_done > 6:
                    break
        return rows
    finally:
        load.write("end " + open("/proc/loadavg").read())
        soak_node.stop(procs)
        time.sleep(2)


def measure(args, scans):
    """Both configurations on one roscore (rospy binds a process to one master)."""
    procs = [soak_node.start_roscore()]
    try:
        time.sleep(3)
        import rospy
        from evidential_octomap.msg import MappingStatus
        rospy.init_node("publish_cost", disable_signals=True)
        for topic, msg_type in TOPICS.items():  # rviz's displays: the outputs are built for them
            module, cls = msg_type.split("/")
            msg_class = getattr(__import__(module + ".msg", fromlist=[cls]), cls)
            rospy.Subscriber("/" + topic, msg_class, lambda m: None, queue_size=1)
        status = {}
        rospy.Subscriber("/evidential_mapping_node/status", MappingStatus,
                         lambda m: status.__setitem__("msg", m), queue_size=10)
        base = {"sensor_model/max_range": 50.0, "publish_rate": 1.0}
        params = {"whole": base, "bounded": dict(base, publish_radius=args.radius,
                                                 full_map_period=args.period)}
        for name in args.only or list(params):
            run_config(name, params[name], args, scans, status)
    finally:
        soak_node.stop(procs)


def generated_by(data):
    """The `evidential_octomap generate` command of a generated sequence (its README says it)."""
    for line in open(os.path.join(data, "README.md")).read().splitlines():
        words = line.split()
        if words[:2] == ["evidential_octomap", "generate"] and "--out" in words:
            del words[words.index("--out"):words.index("--out") + 2]  # a local path
            return "`%s`" % " ".join(words)
    return data


def late(rows, key):
    """Median of `key` over the last third of the samples (the largest maps)."""
    values = sorted(r[key] for r in rows[2 * len(rows) // 3:])
    return values[len(values) // 2]


def report(args, runs, scans):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    commit = subprocess.run(["git", "-C", REPO, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip()
    fig, ax = plt.subplots(figsize=(7, 4))
    lines = ["| configuration | map leaves at the end | views ms (last third, median) | "
             "whole-map ms (last third, median) | longest publish pass ms | insert ms (mean) | "
             "scans inserted / dropped (queue) |",
             "|---|---|---|---|---|---|---|"]
    for name, rows in runs.items():
        leaves = [r["map_leaves"] / 1e6 for r in rows]
        ax.plot(leaves, [r["last_views_ms"] for r in rows], label=name + ": views")
        ax.plot(leaves, [r["last_full_maps_ms"] for r in rows], "--", label=name + ": whole map")
        end = rows[-1]
        lines.append("| %s | %d | %.0f | %.0f | %.0f | %.0f | %d / %d |" % (
            name, end["map_leaves"], late(rows, "last_views_ms"), late(rows, "last_full_maps_ms"),
            end["max_publish_ms"], end["mean_insert_ms"], end["clouds_inserted"],
            end["clouds_dropped_queue"]))
    ax.set_xlabel("map leaves [millions]")
    ax.set_ylabel("time to build and send [ms]")
    ax.set_title("publishing cost against map size (SYNTHETIC sequence)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "publish_cost.png"), dpi=110)
    stamp = "commit %s, %s, load average during the runs: %s" % (
        commit, datetime.date.today().isoformat(), "; ".join(loads(args)))
    text = ["*Generated by `bench/publish_cost.py` (%s): %d scans of a SYNTHETIC sequence (%s), "
            "player at %g Hz, mapping.launch (live profile, max range 50 m), rviz's four topics "
            "subscribed.*" % (stamp, scans, generated_by(args.data), args.rate), ""] + lines
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write("\n".join(text) + "\n")
    print("\n".join(text))
    if args.docs:  # the table into docs/experiments/publishing_cost.md between its markers, the picture beside it
        fig.savefig(os.path.join(REPO, "docs/images/publish_cost.png"), dpi=110)
        path = os.path.join(REPO, "docs/experiments/publishing_cost.md")
        doc = open(path).read()
        begin, end = "<!-- publish-cost: begin -->", "<!-- publish-cost: end -->"
        head, rest = doc.split(begin)
        tail = rest.split(end)[1]
        body = "\n".join(text + ["", "![publishing cost against map size](../images/publish_cost.png)"])
        with open(path, "w") as f:
            f.write(head + begin + "\n" + body + "\n" + end + tail)


def loads(args):
    """The 1-minute load average at the start and end of each run, as recorded."""
    out = []
    for name in run_names(args):
        path = os.path.join(args.out, name, "load.txt")
        words = [line.split()[:2] for line in open(path)] if os.path.exists(path) else []
        out.append("%s %s" % (name, " → ".join(w[1] for w in words) or "not recorded"))
    return out


def read_runs(args):
    """The samples of an earlier run (--report-only)."""
    runs = {}
    for name, label in run_names(args).items():
        with open(os.path.join(args.out, name + ".csv")) as f:
            runs[label] = [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]
    return runs


def run_names(args):
    return {"whole": "everything at 1 Hz",
            "bounded": "views r=%g m, map every %g s" % (args.radius, args.period)}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--data", required=True, help="a generated sequence (evidential_octomap generate)")
    p.add_argument("--out", default="build/publish_cost")
    p.add_argument("--rate", type=float, default=3.0, help="the player's ~rate [Hz]")
    p.add_argument("--scans", type=int, default=0, help="0: every scan of --data")
    p.add_argument("--radius", type=float, default=20.0)
    p.add_argument("--period", type=float, default=30.0)
    p.add_argument("--timeout-s", type=float, default=1800.0)
    p.add_argument("--docs", action="store_true", help="write the table and PNG into docs/")
    p.add_argument("--report-only", action="store_true", help="report the CSVs in --out")
    p.add_argument("--only", action="append", choices=["whole", "bounded"],
                   help="measure only this configuration (the other's CSV from an earlier run)")
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)
    scans = args.scans or len(os.listdir(os.path.join(args.data, "velodyne")))
    if not args.report_only:
        measure(args, scans)
    report(args, read_runs(args), scans)


if __name__ == "__main__":
    main()
