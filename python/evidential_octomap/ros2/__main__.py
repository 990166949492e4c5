"""python -m evidential_octomap.ros2 [--ros-args ...]: runs the mapping node."""
import sys

from .node import main

sys.exit(main())
