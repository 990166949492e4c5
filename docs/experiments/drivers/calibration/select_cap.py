#!/usr/bin/python3
"""Chooses the constants of the adaptive read-out cap, evidence_cap = a * m^k (m: a map's mean
per-point log-evidence), leave-one-family-out, from the L_<name>.npz files of
collect_log_evidence.py, and prints the table of docs/experiments/cap_selection.md.

For each held-out family (a name's prefix before "_": farm, forest, grass, rocky, kitti) (a, k) is
fitted on the other families only, minimising the mean over datasets and protocols of the Brier
score at the cap a * m^k divided by that dataset's best Brier over caps; the held-out family is
then scored with it. The same with one fixed cap for comparison, and the fit on all families
(the library's default constants).

    python3 docs/experiments/drivers/calibration/select_cap.py OUT_DIR
"""
import glob
import os
import sys

import numpy as np

PROTOCOLS = ("reconstruction", "held-out")
CAPS = np.exp(np.linspace(np.log(1.5), np.log(40), 30))
A_GRID = np.exp(np.linspace(np.log(1.0), np.log(10.0), 31))
K_GRID = np.linspace(0.0, 1.0, 21)


def readout(L, cap, C):
    """Projected probabilities and u of dempster log-evidence L (N x C) read with `cap`."""
    total = L.sum(1, keepdims=True)
    L = L * np.where(total > cap, cap / np.maximum(total, 1e-12), 1.0)
    top = L.max(1, keepdims=True)
    mass = np.exp(L - top) * -np.expm1(-L)  # (e^L - 1) / e^top
    floor = np.exp(-top)
    den = floor + mass.sum(1, keepdims=True)
    u = (floor / den)[:, 0]
    return mass / den + u[:, None] / C, u


def auroc(score, positive):
    order = np.argsort(score, kind="stable")
    ranks = np.empty(len(score))
    _, first, counts = np.unique(score[order], return_index=True, return_counts=True)
    ranks[order] = np.repeat(first + (counts + 1) / 2.0, counts)
    n1 = positive.sum()
    n0 = len(positive) - n1
    return (ranks[positive].sum() - n1 * (n1 + 1) / 2) / (n1 * n0) if n1 and n0 else np.nan


def scores(L, labelled, gt, cap, C, brier_only=False):
    """Brier, ECE (10 bins) and AUROC of u for a wrong label, as the CLI's metrics define them
    (a query in a voxel without evidence: uniform p, counted wrong)."""
    p, u = readout(L, cap, C)
    p = np.where(labelled[:, None], p, 1.0 / C)
    onehot = np.zeros_like(p)
    onehot[np.arange(len(gt)), gt] = 1.0
    brier = ((p - onehot) ** 2).sum(1).mean()
    if brier_only:
        return brier
    label = np.where(labelled, p.argmax(1), -1)
    correct = label == gt
    confidence = np.where(labelled, p.max(1), 1.0 / C)
    bins = np.minimum((confidence * 10).astype(int), 9)
    ece = sum((bins == b).mean() * abs(correct[bins == b].mean() - confidence[bins == b].mean())
              for b in range(10) if (bins == b).any())
    return brier, ece, auroc(u[labelled], ~correct[labelled])


def load(out):
    data = {}
    for path in sorted(glob.glob(os.path.join(out, "L_*.npz"))):
        z = np.load(path)
        name = os.path.basename(path)[2:-4]
        data[name] = {"C": int(z["C"])}
        for p in PROTOCOLS:
            data[name][p] = (z[p + "_L"].astype(np.float64), z[p + "_labelled"], z[p + "_gt"],
                             float(z[p + "_m"]))
    return data


def brier_curves(data):
    """Brier over CAPS for every dataset and protocol."""
    curves = {}
    for name, d in data.items():
        for p in PROTOCOLS:
            L, labelled, gt, _ = d[p]
            curves[name, p] = np.array([scores(L, labelled, gt, c, d["C"], True) for c in CAPS])
    return curves


def regret(curves, data, names, a, k):
    ratios = []
    for n in names:
        for p in PROTOCOLS:
            cap = a * data[n][p][3] ** k
            brier = np.interp(np.log(cap), np.log(CAPS), curves[n, p])
            ratios.append(brier / curves[n, p].min())
    return np.mean(ratios)


def fit(curves, data, names, fixed):
    grid = [(a, 0.0) for a in CAPS] if fixed else [(a, k) for a in A_GRID for k in K_GRID]
    return min(grid, key=lambda ak: regret(curves, data, names, *ak))


def family(name):
    return name.split("_")[0]


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    data = load(sys.argv[1])
    curves = brier_curves(data)
    names = sorted(data)
    for fixed in (False, True):
        print("\n%s, leave-one-family-out:\n" % ("One fixed cap" if fixed else "cap = a m^k"))
        print("| dataset (family held out) | m | a, k | cap | Brier rec. (best cap) | ECE rec. "
              "| AUROC u rec. | Brier held-out (best) | ECE held-out | AUROC u held-out |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for held in sorted(set(map(family, names))):
            train = [n for n in names if family(n) != held]
            a, k = fit(curves, data, train, fixed)
            for n in (n for n in names if family(n) == held):
                cells = []
                for p in PROTOCOLS:
                    L, labelled, gt, m = data[n][p]
                    cap = a * m ** k
                    brier, ece, au = scores(L, labelled, gt, cap, data[n]["C"])
                    cells += ["%.3f (%.3f)" % (brier, curves[n, p].min()), "%.3f" % ece,
                              "%.3f" % au]
                    if p == PROTOCOLS[0]:
                        head = "| %s | %.2f | %.2f, %.2f | %.1f" % (n, m, a, k, cap)
                print(head + " | " + " | ".join(cells) + " |")
        a, k = fit(curves, data, names, fixed)
        print("\nFitted on every family: a = %.2f, k = %.2f" % (a, k))


if __name__ == "__main__":
    main()
