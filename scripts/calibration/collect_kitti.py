import sys; sys.path.insert(0, "/tmp/calib")
from harness import *
root = "/work/main/"
classes, scans, evs = load(root + "data/semantickitti_08_first10", root + "config/classes_semantickitti.yaml", source="onehot")
C = classes.num_classes; idx = list(range(10))
for ev in ["learned", "onehot"]:
    out = {}
    for prot, q in [("reconstruction", idx), ("held-out", idx[5:])]:
        t = eo.EvidentialOcTree.load("/tmp/calib/kitti_%s_%s/map.ot" % (ev, prot))
        P, G, E = queries(classes, scans, evs, q)
        L, lab, _ = L_of(t, P)
        out[prot] = (L, lab, G, E)
    (L, lab, G, E), (Lh, labh, Gh, Eh) = out["reconstruction"], out["held-out"]
    np.savez_compressed("/tmp/calib/L_kitti_%s.npz" % ev, L=L.astype(np.float32), lab=lab, G=G, E=E, Y=-np.ones(len(G), int), Lh=Lh.astype(np.float32), labh=labh, Gh=Gh, Eh=Eh)
    print(ev, "ok")
