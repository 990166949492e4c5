"""The ROS 2 mapping node (rclpy over the same core as the CLI, the bag mapper and the ROS 1 node).

    python -m evidential_octomap.ros2 --ros-args -r cloud_in:=/velodyne_points/evidence \\
        -p classes:=config/classes_semantickitti.yaml -p frame_id:=map
    evidential_octomap_ros2 --ros-args --params-file config/ros2/mapping_live.yaml

Needs ``pip install ./python/ros2_interfaces/tf2_msgs
./python/ros2_interfaces/evidential_octomap_msgs ".[ros2]"`` (rclpy and the common interfaces
as wheels; tf2_msgs and the node's services generated). docs/ros2.md has the topics,
parameters and services. The modules here that import no ROS (``latest_queue``, ``status``, ``views``, ``projection``, ``parameters``) hold what
is not ROS; ``node`` only converts messages and wires them to those and to the core.
"""
