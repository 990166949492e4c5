import sys, os; sys.path.insert(0, "/tmp/calib")
from harness import *
for d in sys.argv[1:]:
    name = os.path.basename(d.rstrip("/")); out = "/tmp/calib/L_%s.npz" % name
    if os.path.exists(out): continue
    classes, scans, evs = load(d, d + "/classes.yaml")
    C = classes.num_classes; idx = list(range(len(scans)))
    P, G, E = queries(classes, scans, evs, idx)
    cons = consensus(scans, evs, idx)
    Y = np.concatenate([c[(s.gt != classes.ignore_class) & (s.gt >= 0)] for c, s in zip(cons, scans)])
    tree = build(classes, scans, evs, idx); L, lab, q = L_of(tree, P)
    # held-out: first half mapped, second half queried
    h = len(scans) // 2
    Ph, Gh, Eh = queries(classes, scans, evs, idx[h:])
    treeh = build(classes, scans, evs, idx[:h]); Lh, labh, _ = L_of(treeh, Ph)
    np.savez_compressed(out, L=L.astype(np.float32), lab=lab, G=G, E=E, Y=Y, Lh=Lh.astype(np.float32), labh=labh, Gh=Gh, Eh=Eh)
    print(name, "done", flush=True)
