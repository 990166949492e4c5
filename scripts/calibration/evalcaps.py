import sys, glob, os; sys.path.insert(0, "/tmp/calib")
from harness import *
CAPS = [2, 3, 4, 5, 6, 8, 10, 13, 16, 20, 30]
def capped(L, cap, C):
    T = L.sum(1, keepdims=True); f = np.where(T > cap, cap / np.maximum(T, 1e-12), 1.0)
    return opinion(L * f, C)
def brier_vs(p, lab, y, C):
    ok = y >= 0; p = np.where(lab[:, None], p, 1.0 / C)[ok]; oh = np.zeros_like(p); oh[np.arange(len(p)), y[ok]] = 1
    return ((p - oh) ** 2).sum(1).mean()
rows = {}
for f in sorted(glob.glob("/tmp/calib/L_*.npz")):
    z = np.load(f); name = os.path.basename(f)[2:-4]; C = z["L"].shape[1]
    E = z["E"]; lpp = np.log1p(E / C).sum(1)   # per-point total log-evidence
    r = {"C": C, "med_lpp": float(np.median(lpp))}
    for prot, L, lab, G in [("rec", z["L"], z["lab"], z["G"]), ("held", z["Lh"], z["labh"], z["Gh"])]:
        for cap in CAPS:
            p, u, _ = capped(L.astype(np.float64), cap, C)
            m = metrics(p, lab, G, {"u": u, "1-maxp": 1 - p.max(1)})
            if prot == "rec": m["brier_cons"] = brier_vs(p, lab, z["Y"], C)
            r[(prot, cap)] = m
    rows[name] = r
import pickle; pickle.dump(rows, open("/tmp/calib/caps.pkl", "wb"))
for name, r in rows.items():
    print(name, "C", r["C"], "median per-point log-ev %.2f" % r["med_lpp"])
    for prot in ["rec", "held"]:
        best = min(CAPS, key=lambda c: r[(prot, c)]["brier"])
        line = " ".join("%g:%.3f/%.3f" % (c, r[(prot, c)]["brier"], r[(prot, c)]["ece"]) for c in CAPS)
        print("  ", prot, "best", best, line)
    bc = min(CAPS, key=lambda c: r[("rec", c)]["brier_cons"]); print("   consensus-best cap", bc)
