#!/bin/bash
# Interleaved: sequential in-process reference, batch with 1 and 2 workers (10 scans, chunks of 2).
cd "$(dirname "$0")/../.."
PY="${PY:-build/python-venv/bin/python}"
ARGS="--data data/semantickitti_08_first10 --classes config/classes_semantickitti.yaml --out build/timing/map.ot --chunk-size 2 -q"
for round in 1 2; do
  echo "load $(cat /proc/loadavg)"
  /usr/bin/time -f "sequential (one process): %e s wall, %U+%S s CPU" $PY -c "
from evidential_octomap import batch
batch.map_chunk(batch.MappingJob('data/semantickitti_08_first10', 'config/classes_semantickitti.yaml'), 0, 10)"
  for w in 1 2; do
    echo "load $(cat /proc/loadavg)"
    /usr/bin/time -f "batch --workers $w: %e s wall, %U+%S s CPU" $PY -m evidential_octomap.batch $ARGS --workers $w > /dev/null
  done
done
echo "load $(cat /proc/loadavg)"
