"""Prototype: map once without read-out cap, read L back, evaluate read-outs in numpy."""
import sys, json, numpy as np, evidential_octomap as eo

def load(path, classes_path, nscans=0, source="file"):
    classes = eo.ClassTable.load(classes_path)
    ds = eo.Dataset.open(path, classes)
    n = len(ds) if nscans == 0 else min(nscans, len(ds))
    scans = [ds.load(i) for i in range(n)]
    evs = []
    for s in scans:
        evs.append(s.evidence if source == "file" else eo.derive_evidence(s, classes.num_classes, source))
    return classes, scans, evs

def build(classes, scans, evs, idx, cfg=None):
    cfg = cfg or {}
    c = eo.SemanticConfig(evidence_cap=80.0, **cfg)
    t = eo.EvidentialOcTree(0.2, classes, c)
    for i in idx:
        t.insert_scan(scans[i].points, evs[i], pose=scans[i].pose)
    return t

def queries(classes, scans, evs, idx):
    P, G, E = [], [], []
    for i in idx:
        g = scans[i].gt; m = (g != classes.ignore_class) & (g >= 0)
        P.append(scans[i].points_world()[m]); G.append(g[m]); E.append(evs[i][m])
    return np.concatenate(P), np.concatenate(G), np.concatenate(E)

def L_of(tree, P):
    q = tree.query(P)
    b = q.belief.astype(np.float64); u = q.uncertainty.astype(np.float64)
    L = np.log1p(b / np.maximum(u, 1e-300)[:, None])
    L[q.labels < 0] = 0
    return L, q.labels >= 0, q

def opinion(L, C):
    """Dempster read-out of log-evidence L (N x C): projected p, u, b."""
    m = L.max(1, keepdims=True)
    mass = np.exp(L - m) * -np.expm1(-L)
    floor = np.exp(-m)
    den = floor + mass.sum(1, keepdims=True)
    b = mass / den; u = (floor / den)[:, 0]
    return b + u[:, None] / C, u, b

def auroc(score, pos):
    order = np.argsort(score, kind="stable"); ss = score[order]
    r = np.empty(len(score)); ranks = np.arange(1, len(score) + 1, dtype=float)
    _, first, counts = np.unique(ss, return_index=True, return_counts=True)
    avg = first + (counts + 1) / 2.0
    r[order] = np.repeat(avg, counts); n1 = pos.sum(); n0 = len(pos) - n1
    if n1 == 0 or n0 == 0: return float('nan')
    return (r[pos].sum() - n1 * (n1 + 1) / 2) / (n1 * n0)

def metrics(p, labelled, gt, scores):
    N, C = p.shape
    p = np.where(labelled[:, None], p, 1.0 / C)
    lab = np.where(labelled, p.argmax(1), -1)
    onehot = np.zeros_like(p); onehot[np.arange(N), gt] = 1
    brier = ((p - onehot) ** 2).sum(1).mean()
    conf = np.where(labelled, p.max(1), 1.0 / C); correct = lab == gt
    bins = np.minimum((conf * 10).astype(int), 9); ece = 0
    for k in range(10):
        s = bins == k
        if s.any(): ece += s.mean() * abs(correct[s].mean() - conf[s].mean())
    ious = []
    for c in np.unique(gt):
        tp = ((lab == c) & (gt == c)).sum(); fp = ((lab == c) & (gt != c)).sum(); fn = ((lab != c) & (gt == c)).sum()
        ious.append(tp / (tp + fp + fn))
    out = dict(miou=100 * np.mean(ious), acc=100 * correct.mean(), brier=brier, ece=ece)
    wrong = ~correct[labelled]
    for k, s in scores.items(): out["auroc_" + k] = auroc(s[labelled], wrong)
    return out

def consensus(scans, evs, idx, res=0.2, min_votes=2):
    """Leave-own-scan-out majority class of the other scans' argmax in each point's voxel.
    Returns per scan an int array (-1: no consensus)."""
    keys, scan_id, cls = [], [], []
    for j, i in enumerate(idx):
        k = np.floor(scans[i].points_world() / res).astype(np.int64)
        keys.append(k); scan_id.append(np.full(len(k), j)); cls.append(evs[i].argmax(1))
    K = np.concatenate(keys); S = np.concatenate(scan_id); Cl = np.concatenate(cls)
    C = evs[idx[0]].shape[1]
    _, vox = np.unique(K, axis=0, return_inverse=True); vox = vox.ravel()
    nv = vox.max() + 1
    tot = np.zeros((nv, C), np.int32); np.add.at(tot, (vox, Cl), 1)
    pair = vox * len(idx) + S
    up, pinv = np.unique(pair, return_inverse=True); pinv = pinv.ravel()
    own = np.zeros((len(up), C), np.int32); np.add.at(own, (pinv, Cl), 1)
    other = tot[up // len(idx)] - own
    lab = other.argmax(1); ok = other.max(1) >= min_votes
    lab = np.where(ok, lab, -1)[pinv]
    out, o = [], 0
    for j, i in enumerate(idx):
        n = len(evs[i]); out.append(lab[o:o + n]); o += n
    return out

def point_p(e, s, g):
    ee = s * np.power(e, g)
    return (ee + 1) / (ee.sum(1, keepdims=True) + e.shape[1])

def fit_scale_power(E, y, grid_s=np.exp(np.linspace(-4, 4, 33)), grid_g=np.linspace(0.25, 3, 23)):
    """NLL-minimising e' = s e^g on labelled points (y >= 0)."""
    m = y >= 0; E = E[m]; y = y[m]
    if len(y) > 200000:
        r = np.random.default_rng(0).choice(len(y), 200000, replace=False); E = E[r]; y = y[r]
    best = (1e9, 1, 1)
    for g in grid_g:
        Eg = np.power(E, g)
        for s in grid_s:
            ee = s * Eg
            p = (ee[np.arange(len(y)), y] + 1) / (ee.sum(1) + E.shape[1])
            nll = -np.log(np.maximum(p, 1e-9)).mean()
            if nll < best[0]: best = (nll, s, g)
    return best[1], best[2]

def features(L):
    T = L.sum(1); Ls = np.sort(L, 1)
    top, sec = Ls[:, -1], Ls[:, -2]
    eps = 1e-3
    return np.stack([np.log((top + eps) / (sec + eps)), np.log(T + eps), np.ones(len(L))], 1)

def fit_logistic(X, y, iters=30, l2=1e-3):
    w = np.zeros(X.shape[1])
    for _ in range(iters):
        z = X @ w; p = 1 / (1 + np.exp(-z))
        g = X.T @ (p - y) / len(y) + l2 * w
        H = (X * (p * (1 - p))[:, None]).T @ X / len(y) + l2 * np.eye(len(w))
        w -= np.linalg.solve(H, g)
    return w

def platt_readout(L, w, C):
    """p_top from the logistic model; the rest in proportion to the raw beliefs."""
    p_raw, u, b = opinion(L, C)
    top = L.argmax(1)
    pt = 1 / (1 + np.exp(-(features(L) @ w)))
    pt = np.maximum(pt, 1.0 / C)
    rest = p_raw.copy(); rest[np.arange(len(L)), top] = 0
    rest = rest / np.maximum(rest.sum(1, keepdims=True), 1e-12) * (1 - pt)[:, None]
    rest[np.arange(len(L)), top] = pt
    return rest
