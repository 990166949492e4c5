import sys, glob, os; sys.path.insert(0, "/tmp/calib")
from harness import *
from evalcaps import capped
data = {}
for f in sorted(glob.glob("/tmp/calib/L_*.npz")):
    z = np.load(f); name = os.path.basename(f)[2:-4]; C = z["L"].shape[1]
    lpp = np.log1p(z["E"] / C).sum(1).mean()
    data[name] = dict(C=C, lpp=lpp, rec=(z["L"].astype(np.float64), z["lab"], z["G"]), held=(z["Lh"].astype(np.float64), z["labh"], z["Gh"]))
fam = lambda n: n.split("_")[0]
CAPS = np.exp(np.linspace(np.log(1.5), np.log(40), 30))
cache = {}
def score(name, prot, cap):
    key = (name, prot, round(cap, 4))
    if key not in cache:
        L, lab, G = data[name][prot]; C = data[name]["C"]
        p, u, _ = capped(L, cap, C); cache[key] = metrics(p, lab, G, {"u": u, "1-maxp": 1 - p.max(1)})
    return cache[key]
def brier_only(L, lab, G, cap, C):
    p, _, _ = capped(L, cap, C); p = np.where(lab[:, None], p, 1.0 / C)
    return ((p ** 2).sum(1) - 2 * p[np.arange(len(G)), G] + 1).mean()
sub = {}
for n in data:
    for p in ["rec", "held"]:
        L, lab, G = data[n][p]; i = np.arange(0, len(G), 5)
        sub[(n, p)] = np.array([brier_only(L[i], lab[i], G[i], c, data[n]["C"]) for c in CAPS])
def brier_at(n, p, cap): return np.interp(np.log(cap), np.log(CAPS), sub[(n, p)])
def best_brier(name, prot): return sub[(name, prot)].min()
A = np.exp(np.linspace(np.log(1), np.log(10), 15)); K = np.linspace(0, 1, 11)
def rule_cap(a, k, lpp): return a * lpp ** k
def regret(names, a, k):
    return np.mean([brier_at(n, p, rule_cap(a, k, data[n]["lpp"])) / best_brier(n, p) for n in names for p in ["rec", "held"]])
names = list(data)
for n in names: print(n, "lpp %.2f" % data[n]["lpp"])
for fixed in [False, True]:
    print("=== rule:", "fixed cap" if fixed else "cap = a * lpp^k")
    for hold in sorted(set(map(fam, names))):
        train = [n for n in names if fam(n) != hold]; test = [n for n in names if fam(n) == hold]
        grid = [(a, 0.0) for a in CAPS] if fixed else [(a, k) for a in A for k in K]
        a, k = min(grid, key=lambda ak: regret(train, *ak))
        for n in test:
            cap = rule_cap(a, k, data[n]["lpp"])
            out = []
            for p in ["rec", "held"]:
                m = score(n, p, cap); out.append("%s brier %.3f (best %.3f) ece %.3f aurocU %.3f" % (p, m["brier"], best_brier(n, p), m["ece"], m["auroc_u"]))
            print("hold %-7s a=%.2f k=%.1f -> %-14s cap %.1f | %s" % (hold, a, k, n, cap, " | ".join(out)))
    a, k = min(([(a, 0.0) for a in CAPS] if fixed else [(a, k) for a in A for k in K]), key=lambda ak: regret(names, *ak))
    print("all-data fit a=%.3f k=%.2f" % (a, k))
