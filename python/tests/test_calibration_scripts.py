"""docs/experiments/drivers/calibration/: the numpy read-out and metrics with which select_cap.py
sweeps caps over one stored map (collect_log_evidence.py reads its log-evidence back) agree with the CLI's `eval`
of that map at the same cap, on a tiny generated (SYNTHETIC) sequence."""
import json
import subprocess
import sys

import pytest

from conftest import REPO
from test_kitti import cli_binary

sys.path.insert(0, str(REPO / "docs" / "experiments" / "drivers" / "calibration"))
import collect_log_evidence  # noqa: E402
import select_cap  # noqa: E402


@pytest.mark.skipif(cli_binary() is None, reason="the CLI is built by scripts/test.sh (build/core)")
def test_select_caps_metrics_equal_the_clis_eval(tmp_path):
    cli = str(cli_binary())
    data = tmp_path / "data" / "tiny"
    subprocess.run([cli, "generate", "--scans", "4", "--scene", "forest", "--sensor", "os1-32",
                    "--seed", "5", "--network", "overconfident", "--out", str(data), "-q"],
                   check=True, capture_output=True)
    classes = str(data / "classes.yaml")
    for protocol in select_cap.PROTOCOLS:
        subprocess.run([cli, "map", "--data", str(data), "--classes", classes, "--evidence", "file",
                        "--evidence-cap", "80", "--protocol", protocol, "--no-render", "-q",
                        "--out", str(tmp_path / "maps" / ("tiny_" + protocol))],
                       check=True, capture_output=True)
    collect_log_evidence.collect(str(tmp_path), "tiny", str(data), classes)
    stored = select_cap.load(str(tmp_path))["tiny"]
    for protocol in select_cap.PROTOCOLS:
        for cap in (2.0, 6.5):
            out = tmp_path / ("eval_%s_%g" % (protocol, cap))
            subprocess.run([cli, "eval", "--map", str(tmp_path / "maps" / ("tiny_" + protocol) /
                                                      "map.ot"),
                            "--data", str(data), "--classes", classes, "--evidence", "file",
                            "--protocol", protocol, "--evidence-cap", str(cap), "--out", str(out)],
                           check=True, capture_output=True)
            want = json.load(open(out / "metrics.json"))["map"]
            L, labelled, gt, _ = stored[protocol]
            brier, ece, auroc = select_cap.scores(L, labelled, gt, cap, stored["C"])
            where = "%s, cap %g" % (protocol, cap)
            assert brier == pytest.approx(want["brier"], rel=1e-4), where
            assert ece == pytest.approx(want["ece"], abs=1e-4), where
            assert auroc == pytest.approx(want["error_detection"]["u"]["auroc"], abs=1e-4), where
