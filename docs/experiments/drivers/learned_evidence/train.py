#!/usr/bin/python3
"""Trains the learned evidence head on the bundled SemanticKITTI scans, CROSS-FITTED: fold A is
trained on scans 000000-000004 and gives the evidence of 000005-000009, fold B the other way
round, so no point's evidence comes from a model that saw its labels. Development only (numpy,
Debian's python3-numpy is enough); the map, the CLI and the ROS player only read the result.

    /usr/bin/python3 docs/experiments/drivers/learned_evidence/train.py          # from the repository root

1. `evidential_octomap features` (the C++ CLI; build it first) writes the per-point features,
   so training and inference share one feature implementation (src/evidence/point_features.cpp);
2. each fold trains an MLP F -> 64 -> 32 -> C with the EDL loss of Sensoy et al. 2018 (MSE form,
   KL to Dir(1) annealed over the first epochs), softplus evidence;
3. writes config/learned/semantickitti.model (read by src/evidence/learned_evidence.cpp), the test
   fixture test/fixtures/learned_evidence_points.txt (features and this script's evidence of a
   few fixed points) and the held-out report build/learned_evidence/report.md.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from edl import Adam, Mlp, edl_loss_grad  # noqa: E402
from heldout_metrics import dirichlet_summary, point_metrics  # noqa: E402
from report import write_report  # noqa: E402

FOLDS = {"A": ["000000", "000001", "000002", "000003", "000004"],
         "B": ["000005", "000006", "000007", "000008", "000009"]}


def dump_features(cli, data, classes, out):
    if not os.path.exists(cli):
        sys.exit("train.py: %s not found; build the CLI first (bash scripts/test.sh, or cmake "
                 "--build build/core --target evidential_octomap_cli)" % cli)
    subprocess.run([cli, "features", "--data", data, "--classes", classes, "--out", out, "-q"],
                   check=True)


def load_scans(features_dir):
    with open(os.path.join(features_dir, "index.json")) as f:
        index = json.load(f)
    scans = {}
    for s in index["scans"]:
        stem = os.path.join(features_dir, s["name"])
        scans[s["name"]] = {"x": np.load(stem + ".features.npy"),
                            "gt": np.load(stem + ".gt.npy")[:, 0],
                            "pred": np.load(stem + ".pred.npy")[:, 0],
                            "fingerprint": s["fingerprint"]}
    return index, scans


def stack(scans, names, ignore):
    x = np.concatenate([scans[n]["x"] for n in names])
    gt = np.concatenate([scans[n]["gt"] for n in names])
    keep = gt != ignore
    return x[keep], gt[keep]


def class_weights(y, num_classes, power):
    """w_c proportional to frequency^-power, mean 1 over the training points, at most 10."""
    counts = np.bincount(y, minlength=num_classes).astype(np.float64)
    w = np.where(counts > 0, (counts / counts.max() + 1e-12) ** -power, 0.0)
    w = np.minimum(w / (w[y].mean()), 10.0)
    return (w / w[y].mean()).astype(np.float32)


def train_fold(x, y, num_classes, args, seed):
    rng = np.random.default_rng(seed)
    mlp = Mlp([x.shape[1]] + args.hidden + [num_classes], rng)
    mlp.mean = x.mean(axis=0).astype(np.float32)
    std = x.std(axis=0)
    mlp.std = np.where(std > 1e-6, std, 1.0).astype(np.float32)
    w_class = class_weights(y, num_classes, args.class_weight_power)
    adam = Adam(mlp.params(), lr=args.lr, weight_decay=args.weight_decay)
    for epoch in range(args.epochs):
        kl = args.kl_max * min(1.0, epoch / float(args.kl_anneal_epochs))
        lr = args.lr * (0.5 * (1 + np.cos(np.pi * epoch / args.epochs)))  # cosine decay
        adam.lr = lr
        order = rng.permutation(len(y))[:args.points_per_epoch]
        total, t0 = 0.0, time.process_time()
        for b in range(0, len(order), args.batch):
            idx = order[b:b + args.batch]
            _, cache = mlp.forward(x[idx], keep=True)
            loss, g = edl_loss_grad(cache[-1], y[idx], kl, w_class[y[idx]])
            adam.step(mlp.params(), mlp.backward(cache, g))
            total += loss * len(idx)
        print("  epoch %2d  kl %.2f  lr %.5f  loss %.4f  (%.1f s CPU)"
              % (epoch, kl, lr, total / len(order), time.process_time() - t0), flush=True)
    return mlp


def write_model(path, folds, feature_names, num_classes, description):
    def line(values):
        return " ".join("%.9g" % v for v in np.asarray(values, np.float32).ravel())
    with open(path, "w") as f:
        f.write("evidential_octomap_learned_evidence 1\n")
        f.write("classes %d\n" % num_classes)
        f.write("features %d %s\n" % (len(feature_names), " ".join(feature_names)))
        f.write("description %s\n" % description)
        f.write("folds %d\n" % len(folds))
        for name, fold in folds.items():
            mlp = fold["mlp"]
            f.write("fold %s trained_on %d %s\n" % (name, len(fold["fingerprints"]),
                                                     " ".join(fold["fingerprints"])))
            f.write("normalise %s\n%s\n" % (line(mlp.mean), line(mlp.std)))
            f.write("layers %d\n" % len(mlp.w))
            for k, (w, b) in enumerate(zip(mlp.w, mlp.b)):
                act = "softplus" if k + 1 == len(mlp.w) else "relu"
                f.write("dense %d %d %s\n%s\n%s\n" % (w.shape[1], w.shape[0], act, line(w), line(b)))
        f.write("end\n")


def read_model(path):
    """The folds as written (float32 values parsed back), for the fixture's expected values."""
    tokens = open(path).read().split()
    pos = tokens.index("folds")
    nf = int(tokens[tokens.index("features") + 1])
    folds, p = {}, pos + 2
    for _ in range(int(tokens[pos + 1])):
        name, n = tokens[p + 1], int(tokens[p + 3])
        p += 4 + n + 1
        mlp = Mlp([1, 1], np.random.default_rng(0))
        mlp.mean = np.array(tokens[p:p + nf], np.float32)
        mlp.std = np.array(tokens[p + nf:p + 2 * nf], np.float32)
        p += 2 * nf + 1
        layers = int(tokens[p])
        p += 1
        mlp.w, mlp.b = [], []
        for _ in range(layers):
            a, b = int(tokens[p + 1]), int(tokens[p + 2])
            p += 4
            mlp.w.append(np.array(tokens[p:p + a * b], np.float32).reshape(b, a))
            mlp.b.append(np.array(tokens[p + a * b:p + a * b + b], np.float32))
            p += a * b + b
        folds[name] = mlp
    return folds


def float64_forward(mlp, x):
    a = (x.astype(np.float64) - mlp.mean) / mlp.std
    for k, (w, b) in enumerate(zip(mlp.w, mlp.b)):
        z = a @ w.T.astype(np.float64) + b
        a = np.maximum(z, 0.0) if k + 1 < len(mlp.w) else np.where(z > 20, z, np.log1p(np.exp(np.minimum(z, 20))))
    return a


def write_fixture(path, model_path, scans, ignore, per_fold=4):
    """Features and float64 evidence of a few fixed held-out points per fold, and the argmax
    accuracy of the first scan of each fold's held-out set (an end-to-end check of the C++
    features + inference on the bundled data)."""
    folds = read_model(model_path)
    rng = np.random.default_rng(7)
    with open(path, "w") as f:
        f.write("# Written by docs/experiments/drivers/learned_evidence/train.py: fold, raw features, the script's "
                "float64 evidence of the model as written (test_learned_evidence.cpp).\n")
        for name, mlp in folds.items():
            other = [s for s in FOLDS if s != name][0]
            x = scans[FOLDS[other][0]]["x"]
            rows = x[rng.choice(len(x), per_fold, replace=False)]
            for r, e in zip(rows, float64_forward(mlp, rows)):
                f.write("fold %s features %s evidence %s\n" % (
                    name, " ".join("%.9g" % v for v in r), " ".join("%.9g" % v for v in e)))
        for name, mlp in folds.items():
            stem = FOLDS[[s for s in FOLDS if s != name][0]][0]
            keep = scans[stem]["gt"] != ignore
            pred = float64_forward(mlp, scans[stem]["x"][keep]).argmax(axis=1)
            f.write("scan %s fold %s accuracy %.6f\n" % (stem, name, (pred == scans[stem]["gt"][keep]).mean()))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.abspath(os.path.join(here, "..", "..", "..", ".."))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default=os.path.join(root, "build/core/src/tools/evidential_octomap"))
    ap.add_argument("--data", default=os.path.join(root, "data/semantickitti_08_first10"))
    ap.add_argument("--classes", default=os.path.join(root, "config/classes_semantickitti.yaml"))
    ap.add_argument("--work", default=os.path.join(root, "build/learned_evidence"))
    ap.add_argument("--model", default=os.path.join(root, "config/learned/semantickitti.model"))
    ap.add_argument("--fixture", default=os.path.join(root, "test/fixtures/learned_evidence_points.txt"))
    ap.add_argument("--hidden", type=int, nargs="+", default=[64, 32])
    ap.add_argument("--epochs", type=int, default=12)
    ap.add_argument("--kl-anneal-epochs", type=int, default=6)
    ap.add_argument("--kl-max", type=float, default=0.05,
                    help="weight of the KL term once annealed (Sensoy et al.: 1; measured: 1 zeroes the evidence of 24 %% of held-out points and drops accuracy to 78 %%, 0.1 gives 88.8 %%, 0.02 89.6 %%)")
    ap.add_argument("--points-per-epoch", type=int, default=600000)
    ap.add_argument("--batch", type=int, default=1024)
    ap.add_argument("--lr", type=float, default=2e-3)
    ap.add_argument("--weight-decay", type=float, default=1e-4)
    ap.add_argument("--class-weight-power", type=float, default=0.25)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--fixture-only", action="store_true",
                    help="no training: rewrite the fixture and the report of the existing --model")
    args = ap.parse_args()

    features_dir = os.path.join(args.work, "features")
    dump_features(args.cli, args.data, args.classes, features_dir)
    index, scans = load_scans(features_dir)
    C, ignore = index["num_classes"], index["ignore_class"]
    if not args.fixture_only:
        train_and_write(args, index, scans)
    write_fixture(args.fixture, args.model, scans, ignore)
    written = read_model(args.model)
    held_out = {}
    for name, train_names in FOLDS.items():
        for other in (n for n in scans if n not in train_names):
            held_out[other] = float64_forward(written[name], scans[other]["x"])
    os.makedirs(args.work, exist_ok=True)
    write_report(os.path.join(args.work, "report.md"), index, scans, held_out, FOLDS, args)
    print("wrote %s (%d bytes), %s, %s/report.md" % (args.model, os.path.getsize(args.model),
                                                      args.fixture, args.work))


def train_and_write(args, index, scans):
    C, ignore = index["num_classes"], index["ignore_class"]
    folds = {}
    for name, train_names in FOLDS.items():
        x, y = stack(scans, train_names, ignore)
        print("fold %s: %d labelled points of scans %s" % (name, len(y), ", ".join(train_names)))
        mlp = train_fold(x, y, C, args, args.seed)
        folds[name] = {"mlp": mlp, "fingerprints": [scans[n]["fingerprint"] for n in train_names]}
    description = ("learned (cross-fitted) evidential MLP %s, EDL loss (Sensoy 2018), trained on "
                   "SemanticKITTI 08 scans 0-4 (fold A) and 5-9 (fold B) by "
                   "docs/experiments/drivers/learned_evidence/train.py" % "-".join(map(str, [len(index["feature_names"])] + args.hidden + [C])))
    os.makedirs(os.path.dirname(args.model), exist_ok=True)
    write_model(args.model, folds, index["feature_names"], C, description)


if __name__ == "__main__":
    main()
