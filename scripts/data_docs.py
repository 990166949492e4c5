#!/usr/bin/python3
"""Pictures of docs/data.md from generated (SYNTHETIC) datasets: a top-down view of a scene
family (points of every scan in the world frame, coloured by ground-truth class) and reliability
diagrams of the network presets (from each dataset's network_metrics.json).

  data_docs.py topdown DATASET OUT.png [--stamp TEXT]
  data_docs.py reliability OUT.png --stamp TEXT NAME=DATASET ...

Reads the dataset as evaluation/dataset.h does: T_W_S = inv(Tr) P Tr.
"""
import argparse
import json
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import yaml  # noqa: E402


def read_matrix_lines(path, key=None):
    rows = []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if key is not None:
                if parts[0] != key:
                    continue
                parts = parts[1:]
            m = np.eye(4)
            m[:3, :] = np.array(parts, dtype=float).reshape(3, 4)
            rows.append(m)
    return rows


def load_points(data, every=1, max_scans=None):
    tr = read_matrix_lines(os.path.join(data, "calib.txt"), "Tr:")[0]
    poses = read_matrix_lines(os.path.join(data, "poses.txt"))
    stems = sorted(f[:-4] for f in os.listdir(os.path.join(data, "velodyne")) if f.endswith(".bin"))
    if max_scans:
        stems = stems[:max_scans]
    xyz, labels = [], []
    tr_inv = np.linalg.inv(tr)
    for stem in stems[::every]:
        pts = np.fromfile(os.path.join(data, "velodyne", stem + ".bin"), dtype=np.float32)
        pts = pts.reshape(-1, 4)[:, :3].astype(np.float64)
        lab = np.fromfile(os.path.join(data, "labels", stem + ".label"), dtype=np.uint32) & 0xFFFF
        t = tr_inv @ poses[int(stem)] @ tr
        xyz.append(pts @ t[:3, :3].T + t[:3, 3])
        labels.append(lab)
    return np.concatenate(xyz), np.concatenate(labels), [tr_inv @ p @ tr for p in poses]


def load_table(data):
    with open(os.path.join(data, "classes.yaml")) as f:
        table = yaml.safe_load(f)
    names = [c["name"] for c in table["classes"]]
    colors = np.array([c["color"] for c in table["classes"]], dtype=float) / 255.0
    lut = {int(raw): cls for raw, cls in table["learning_map"].items()}
    return names, colors, lut


def topdown(args):
    names, colors, lut = load_table(args.data)
    xyz, raw, poses = load_points(args.data, every=args.every)
    lut_arr = np.zeros(int(raw.max()) + 1, dtype=int)
    for r, c in lut.items():
        if r < len(lut_arr):
            lut_arr[r] = c
    cls = lut_arr[raw]
    traj = np.array([p[:3, 3] for p in poses])
    cx, cy = traj[:, 0].mean(), traj[:, 1].mean()
    half = args.extent or max(np.ptp(xyz[:, 0]), np.ptp(xyz[:, 1])) / 2
    res = args.resolution
    n = int(2 * half / res)
    i = ((xyz[:, 0] - (cx - half)) / res).astype(int)
    j = ((xyz[:, 1] - (cy - half)) / res).astype(int)
    ok = (i >= 0) & (i < n) & (j >= 0) & (j < n)
    i, j, z, cls = i[ok], j[ok], xyz[ok, 2], cls[ok]
    # As seen from above: each pixel shows the class of its highest point.
    order = np.argsort(z)
    img = np.zeros((n, n, 3))
    img[j[order], i[order]] = colors[cls[order]]
    fig, ax = plt.subplots(figsize=(7.5, 7.5), dpi=110)
    ax.imshow(img, origin="lower", extent=(cx - half, cx + half, cy - half, cy + half),
              interpolation="nearest")
    ax.plot(traj[:, 0], traj[:, 1], color="white", lw=0.8)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    present = sorted(set(cls.tolist()))
    handles = [plt.Line2D([], [], marker="s", ls="", color=colors[k], label=names[k])
               for k in present]
    handles.append(plt.Line2D([], [], color="white", label="trajectory"))
    leg = ax.legend(handles=handles, loc="upper right", fontsize=7, framealpha=0.85)
    leg.get_frame().set_facecolor("#dddddd")
    ax.set_title(args.title or "SYNTHETIC", fontsize=10)
    if args.stamp:
        fig.text(0.01, 0.005, args.stamp, fontsize=7, color="gray")
    fig.tight_layout()
    fig.savefig(args.out)


def reliability(args):
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.8), dpi=110)
    for spec in args.datasets:
        name, data = spec.split("=", 1)
        with open(os.path.join(data, "network_metrics.json")) as f:
            m = json.load(f)
        for ax, key, label in ((axes[0], "softmax", "max softmax(z/T)"),
                               (axes[1], "dirichlet_mean", "Dirichlet mean (e_k+1)/S")):
            bins = [b for b in m["reliability"][key] if b["count"] > 0]
            ax.plot([b["confidence"] for b in bins], [b["accuracy"] for b in bins], "o-",
                    label="%s (acc %.2f, AUROC u %.2f, ECE %.3f)" % (
                        name, m["accuracy"], m["auroc_vacuity"],
                        m["ece_softmax" if key == "softmax" else "ece_dirichlet_mean"]))
            ax.set_xlabel("confidence of the predicted class (" + label + ")")
    for ax in axes:
        ax.plot([0, 1], [0, 1], "k--", lw=0.8)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.set_ylabel("accuracy")
        ax.legend(fontsize=7, loc="upper left")
        ax.grid(alpha=0.3)
    fig.suptitle("SYNTHETIC: per-point reliability of the network presets", fontsize=10)
    if args.stamp:
        fig.text(0.01, 0.005, args.stamp, fontsize=7, color="gray")
    fig.tight_layout()
    fig.savefig(args.out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("topdown")
    t.add_argument("data")
    t.add_argument("out")
    t.add_argument("--every", type=int, default=1, help="use every k-th scan")
    t.add_argument("--extent", type=float, default=0.0, help="half width of the view [m]")
    t.add_argument("--resolution", type=float, default=0.2, help="pixel size [m]")
    t.add_argument("--title", default="")
    t.add_argument("--stamp", default="")
    r = sub.add_parser("reliability")
    r.add_argument("out")
    r.add_argument("datasets", nargs="+")
    r.add_argument("--stamp", default="")
    args = p.parse_args()
    topdown(args) if args.cmd == "topdown" else reliability(args)


if __name__ == "__main__":
    main()
