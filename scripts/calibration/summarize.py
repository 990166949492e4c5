#!/usr/bin/python3
"""Cross-dataset summary of scripts/calibration/cross_dataset.sh's compare tables: per dataset,
protocol and evidence source, mIoU (all queries), Brier, ECE and AUROC of u of every row.
    python3 scripts/calibration/summarize.py out/cross_dataset > docs/calibration_tables.md"""
import glob, os, re, subprocess, sys, datetime

root = sys.argv[1]
GENERATED = ("forest_good", "grassland_poor", "rocky_overconfident_x5", "farm_underconfident_x0.3")
commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
print("# Cross-dataset table (produced by scripts/calibration/summarize.py; commit %s, %s)\n"
      % (commit, datetime.date.today()))
print("Every row of a section on the same queries; generated datasets are **synthetic**. Columns: "
      "mIoU over all queries %, Brier, ECE, AUROC of u for the voxel's label being wrong. "
      "Bootstrap intervals of each row against dempster are in each compare.md.\n")
print("| dataset | protocol | source | row | mIoU all % | Brier | ECE | AUROC u |")
print("|---|---|---|---|---|---|---|---|")
for f in sorted(glob.glob(os.path.join(root, "compare_*", "compare.md"))):
    base = os.path.basename(os.path.dirname(f))[len("compare_"):]
    name = base
    section, rows, auroc = None, {}, {}
    def flush():
        for key, (miou, brier, ece) in rows.items():
            src, row = key
            print("| %s%s | %s | %s | %s | %s | %s | %s | %s |" % (
                name, " (synthetic)" if name.split(" ")[0] in GENERATED else "", section, src, row, miou, brier,
                ece, auroc.get(key, "–")))
    table = 0
    for line in open(f):
        m = re.match(r"## (.*), protocol \*\*(\S+)\*\*", line)
        if m:
            if section: flush()
            label = m.group(1).replace("**", "")
            name = label if label.startswith(base) or "RELLIS" in label else base + " / " + label
            section, rows, auroc, table = m.group(2), {}, {}, 0
            continue
        if line.startswith("| mIoU") or line.startswith("| | mIoU") or "AUROC u" in line:
            table += 1
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if section is None or len(cells) < 8 or cells[0] in ("", "–", "---", "source", "evidence"):
            continue
        if "oracle" in cells[1] or "majority" in cells[1] or cells[2].startswith(("+", "-")):
            continue
        key = (cells[0], cells[1])
        if len(cells) >= 16 and key not in rows:
            rows[key] = (cells[4], cells[10], cells[12])
        elif len(cells) in (13, 12) and key in rows:
            auroc[key] = cells[4]
    if section: flush()
