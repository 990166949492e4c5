"""examples/map_bundled_scans.py runs, stays within 20 lines and writes the map it reports."""
import re
import subprocess
import sys

import evidential_octomap as eo
from conftest import REPO

EXAMPLE = REPO / "examples" / "map_bundled_scans.py"


def test_example_maps_the_bundled_scans(tmp_path):
    assert len(EXAMPLE.read_text().splitlines()) <= 20
    out = subprocess.run([sys.executable, str(EXAMPLE), str(tmp_path / "map.ot"), "2"], check=True,
                         capture_output=True, text=True).stdout
    found = re.fullmatch(r"(\d+) leaves; coverage ([\d.]+)% mIoU ([\d.]+)% Acc ([\d.]+)%\n", out)
    assert found, out
    assert eo.load(tmp_path / "map.ot").num_leaves == int(found.group(1))
    assert all(0 < float(v) <= 100 for v in found.groups()[1:])
