"""Per-point metrics of class probabilities on GT-labelled points (numpy only):
accuracy, mIoU (classes present in GT), multi-class Brier score sum_c (p_c - y_c)^2, NLL,
ECE (15 equal-width confidence bins on max p) and AUROC of an uncertainty for "the argmax is
wrong" (rank statistic, ties averaged)."""
import numpy as np


def miou(pred, gt, num_classes, ignore):
    ious = []
    for c in range(num_classes):
        if c == ignore or not (gt == c).any():
            continue
        tp = np.sum((pred == c) & (gt == c))
        ious.append(tp / (np.sum(pred == c) + np.sum(gt == c) - tp))
    return float(np.mean(ious))


def auroc(score, positive):
    """P(score of a random positive > score of a random negative), ties count one half."""
    positive = positive.astype(bool)
    n_pos, n_neg = positive.sum(), (~positive).sum()
    if n_pos == 0 or n_neg == 0:
        return float("nan")
    order = np.argsort(score, kind="mergesort")
    s = score[order]
    ranks = np.empty(len(s), np.float64)
    starts = np.r_[0, np.flatnonzero(np.diff(s)) + 1]
    ends = np.r_[starts[1:], len(s)]
    for a, b in zip(starts, ends):
        ranks[a:b] = 0.5 * (a + b - 1) + 1.0
    r = np.empty_like(ranks)
    r[order] = ranks
    return float((r[positive].sum() - n_pos * (n_pos + 1) / 2.0) / (n_pos * n_neg))


def ece(prob, gt, bins=15):
    conf = prob.max(axis=1)
    correct = prob.argmax(axis=1) == gt
    edges = np.linspace(0.0, 1.0, bins + 1)
    idx = np.clip(np.digitize(conf, edges[1:-1]), 0, bins - 1)
    total = 0.0
    for b in range(bins):
        m = idx == b
        if m.any():
            total += m.sum() * abs(correct[m].mean() - conf[m].mean())
    return float(total / len(gt))


def point_metrics(prob, gt, num_classes, ignore, uncertainty=None):
    """prob: N x C class probabilities; uncertainty: N values (None: constant)."""
    pred = prob.argmax(axis=1)
    wrong = pred != gt
    onehot = np.zeros_like(prob)
    onehot[np.arange(len(gt)), gt] = 1.0
    out = {
        "accuracy": float(1.0 - wrong.mean()),
        "miou": miou(pred, gt, num_classes, ignore),
        "brier": float(((prob - onehot) ** 2).sum(axis=1).mean()),
        "nll": float(-np.log(np.maximum(prob[np.arange(len(gt)), gt], 1e-12)).mean()),
        "ece": ece(prob, gt),
        "auroc_u": 0.5 if uncertainty is None else auroc(uncertainty, wrong),
        "auroc_1_minus_maxp": auroc(1.0 - prob.max(axis=1), wrong),
    }
    return out


def dirichlet_summary(evidence):
    """Projected probabilities alpha / S and vacuity u = C / S of evidence e (N x C)."""
    alpha = evidence.astype(np.float64) + 1.0
    s = alpha.sum(axis=1, keepdims=True)
    return alpha / s, (evidence.shape[1] / s)[:, 0]
