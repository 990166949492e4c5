#!/usr/bin/python3
"""How much a neighbour voxel gets of a point's evidence, relative to the point's own voxel.

    neighbour_weights.py [SIGMA0 ...]      (default: 1 0.7)

Prints the Markdown table of docs/experiments/results.md ("How dempster and ebs weigh a neighbour") from
the formulas of docs/design.md: the sparse kernel k = sigma0 k'(d / L) with the default support
L = l beta e (l = 0.3 m, beta = 1), distances measured to the neighbour voxel's cube; ebs adds
k p (linear in k); dempster adds log1p(k b / (1 - k (1 - u))) for the point's class (b = 1 - u).
"""
import math
import sys

SUPPORT = 0.3 * 1.0 * math.e
DISTANCES = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5]
POINTS = [("calibrated onehot point", 0.16), ("confident point", 0.05), ("weak point", 0.5)]


def kernel(d, sigma0):
    r = d / SUPPORT
    if r >= 1.0:
        return 0.0
    shape = (2 + math.cos(2 * math.pi * r)) / 3 * (1 - r) + math.sin(2 * math.pi * r) / (2 * math.pi)
    return min(1.0, sigma0 * shape)


def dempster(k, u):
    return math.log1p(k * (1 - u) / (1 - k * (1 - u)))


def row(label, weight):
    own = weight(0.0)
    return "| %s | %s |" % (label, " | ".join("%.2f" % (weight(d) / own) for d in DISTANCES))


def main():
    sigmas = [float(s) for s in sys.argv[1:]] or [1.0, 0.7]
    lines = ["| distance to the voxel | " + " | ".join(
        "0 (own voxel)" if d == 0 else "%.1f m" % d for d in DISTANCES) + " |",
        "|---|" + "---|" * len(DISTANCES),
        row("kernel k (`ebs`: its relative weight, any σ0)", lambda d: kernel(d, 1.0))]
    for sigma0 in sigmas:
        for name, u in POINTS:
            lines.append(row("`dempster` σ0 = %g, %s (u = %g)" % (sigma0, name, u),
                             lambda d, s=sigma0, u=u: dempster(kernel(d, s), u)))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
