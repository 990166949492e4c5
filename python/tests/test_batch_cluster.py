"""The batch on a real Dask cluster: a `dask scheduler` and two `dask worker` processes started
apart from the client (as on N machines, here on one), tiles on a shared directory; one worker
is killed with SIGKILL while chunks are being mapped, and the run still finishes with the map
one process builds."""
import json
import os
import signal
import subprocess
import sys
import time

import pytest

import evidential_octomap as eo
from evidential_octomap import batch
from conftest import KITTI, REPO
from test_batch import EDGE, JOB, assert_same_map, sequential_map

pytest.importorskip("distributed")
DASK = os.path.join(os.path.dirname(sys.executable), "dask")
SCANS = 6


def wait_for(condition, seconds, what):
    deadline = time.monotonic() + seconds
    while not condition():
        if time.monotonic() > deadline:
            raise TimeoutError(f"no {what} after {seconds} s")
        time.sleep(0.2)


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two single-threaded workers without nannies (a killed worker stays dead);
    yields (scheduler address, worker processes)."""
    scheduler_file = tmp_path / "scheduler.json"
    quiet = dict(stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    processes = [subprocess.Popen([DASK, "scheduler", "--port", "0", "--dashboard-address", ":0",
                                   "--scheduler-file", str(scheduler_file)], **quiet)]
    try:
        wait_for(scheduler_file.exists, 60, "scheduler file")
        address = json.loads(scheduler_file.read_text())["address"]
        workers = [subprocess.Popen([DASK, "worker", address, "--nthreads", "1", "--no-nanny",
                                     "--dashboard-address", ":0"],
                                    env=dict(os.environ, OMP_NUM_THREADS="1"), **quiet)
                   for _ in range(2)]
        processes += workers
        from distributed import Client

        with Client(address) as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for p in reversed(processes):
            p.kill()
            p.wait()


def test_a_worker_killed_mid_run_leaves_the_map_equal(cluster, tmp_path):
    address, workers = cluster
    out, whole = tmp_path / "shared" / "tiles", tmp_path / "shared" / "map.ot"
    run = subprocess.Popen([sys.executable, "-m", "evidential_octomap.batch", "--scheduler",
                            address, "--data", str(KITTI), "--classes", JOB.classes, "--out",
                            str(out), "--global-map", str(whole), "--scans", str(SCANS),
                            "--chunk-size", "1", "--tile-edge", str(EDGE), "--set",
                            "max_range=30", "-q"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    work = out / ".work"
    # The first chunk's tiles are on disk: mapping is under way on both workers.
    wait_for(lambda: work.exists() and any(work.iterdir()), 300, "chunk written")
    os.kill(workers[0].pid, signal.SIGKILL)
    assert workers[0].wait() == -signal.SIGKILL
    assert run.poll() is None  # killed while the batch was still running
    assert len(list(work.iterdir())) < SCANS  # and before every chunk was mapped
    stdout, stderr = run.communicate(timeout=600)
    assert run.returncode == 0, stderr
    assert "on 2 workers" in stderr and f"of {SCANS} scans" in stdout
    tiled = eo.TiledMap(str(out))
    assert_same_map(tiled.global_map(), sequential_map(JOB, SCANS))
    assert eo.load(str(whole)).to_bytes() == tiled.global_map().to_bytes()
