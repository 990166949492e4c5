"""Markdown report of the cross-fitted evidence on the scans each fold did not see: per-point
metrics beside the bundled network's hard predictions, and where the uncertainty u is high
(range, class borders, classes)."""
import json

import numpy as np

from heldout_metrics import dirichlet_summary, point_metrics

RANGE_BINS = [0, 10, 20, 30, 50, 1000]


def metrics_rows(gt, pred, evidence, C, ignore, magnitude=20.0):
    hard = np.zeros((len(gt), C))
    hard[np.arange(len(gt)), pred] = 1.0
    onehot_e = hard * magnitude
    p_onehot, _ = dirichlet_summary(onehot_e)
    p_learned, u_learned = dirichlet_summary(evidence)
    return [("network's hard predictions (p = one-hot)", point_metrics(hard, gt, C, ignore)),
            ("derived one-hot, E = 20 (p = alpha / S)", point_metrics(p_onehot, gt, C, ignore)),
            ("**learned (cross-fitted)** (p = alpha / S)",
             point_metrics(p_learned, gt, C, ignore, u_learned))], u_learned, p_learned


def table(rows):
    out = ["| per-point input | Acc % | mIoU % | Brier | NLL | ECE | AUROC u | AUROC 1-max p |",
           "|---|---|---|---|---|---|---|---|"]
    for name, m in rows:
        out.append("| %s | %.1f | %.1f | %.4f | %.3f | %.4f | %.3f | %.3f |" % (
            name, 100 * m["accuracy"], 100 * m["miou"], m["brier"], m["nll"], m["ece"],
            m["auroc_u"], m["auroc_1_minus_maxp"]))
    return out


def structure(title, groups, u, wrong, net_wrong):
    out = ["| %s | points | mean u | learned error %% | network error %% |" % title,
           "|---|---|---|---|---|"]
    for name, m in groups:
        if m.sum() == 0:
            continue
        out.append("| %s | %d | %.3f | %.1f | %.1f |" % (name, m.sum(), u[m].mean(),
                                                         100 * wrong[m].mean(), 100 * net_wrong[m].mean()))
    return out


def write_report(path, index, scans, held_out, folds, args):
    C, ignore, names = index["num_classes"], index["ignore_class"], index["class_names"]
    order = sorted(held_out)
    x = np.concatenate([scans[n]["x"] for n in order])
    gt = np.concatenate([scans[n]["gt"] for n in order])
    pred = np.concatenate([scans[n]["pred"] for n in order])
    ev = np.concatenate([held_out[n] for n in order])
    keep = gt != ignore
    x, gt, pred, ev = x[keep], gt[keep], pred[keep], ev[keep]
    lines = ["# Learned evidence: held-out per-point figures", "",
             "Every point's evidence comes from the fold that did not see its scan's labels "
             "(fold A: scans %s; fold B: scans %s). %d GT-labelled points (class %s excluded) "
             "of scans %s. Brier = sum over classes of (p_c - y_c)^2; ECE over 15 bins of max p; "
             "AUROC of an uncertainty for \"argmax is wrong\"." % (
                 "-".join([folds["A"][0], folds["A"][-1]]), "-".join([folds["B"][0], folds["B"][-1]]),
                 len(gt), names[ignore], ", ".join(order)), "",
             "Training: %s" % json.dumps({k: v for k, v in vars(args).items()
                                          if k not in ("cli", "data", "classes", "work", "model", "fixture")}), ""]
    rows, u, p = metrics_rows(gt, pred, ev, C, ignore)
    lines += ["## All ten scans (each from its held-out fold)", ""] + table(rows) + [""]
    for fold, train in folds.items():
        m = np.concatenate([np.full((scans[n]["gt"] != ignore).sum(), n not in train) for n in order])
        r, _, _ = metrics_rows(gt[m], pred[m], ev[m], C, ignore)
        lines += ["## Scans not in fold %s's training set (evidence of fold %s)" % (fold, fold), ""] + table(r) + [""]
    wrong = p.argmax(axis=1) != gt
    net_wrong = pred != gt
    rng = x[:, 0]
    agreement = x[np.arange(len(pred)), 13 + C + pred]  # share of neighbours with the same prediction
    lines += ["## Where u is high", ""]
    lines += structure("range [m]", [("%d-%d" % (a, b), (rng >= a) & (rng < b))
                                     for a, b in zip(RANGE_BINS[:-1], RANGE_BINS[1:])], u, wrong, net_wrong) + [""]
    lines += structure("neighbours predicted like the point", [
        ("all (interior)", agreement >= 0.999), ("50-99 % (border)", (agreement >= 0.5) & (agreement < 0.999)),
        ("< 50 % (island)", agreement < 0.5)], u, wrong, net_wrong) + [""]
    counts = np.bincount(gt, minlength=C)
    groups = [(names[c] + " (%.2f %%)" % (100.0 * counts[c] / len(gt)), gt == c)
              for c in np.argsort(-counts) if counts[c] > 0]
    lines += structure("GT class (share of points)", groups, u, wrong, net_wrong) + [""]
    qs = np.quantile(u, np.linspace(0, 1, 11))
    dec = [("%.3f-%.3f" % (qs[k], qs[k + 1]), (u >= qs[k]) & ((u < qs[k + 1]) if k < 9 else (u <= qs[k + 1])))
           for k in range(10)]
    lines += structure("u decile", dec, u, wrong, net_wrong) + [""]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
