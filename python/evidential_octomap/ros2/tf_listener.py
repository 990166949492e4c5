"""/tf and /tf_static taken on a node and executor of their own, spun by a thread of their own
(tf2_ros's TransformListener with spin_thread), into a WaitingTf. Under the mapping node's
executor, busy with clouds of 11 MB, /tf stalled for more than a second in some runs, and the
clouds waiting for those transforms were dropped."""
import threading

from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from tf2_msgs.msg import TFMessage

from .tf_wait import WaitingTf

TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE)
TF_STATIC_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.TRANSIENT_LOCAL)


class TfListener:
    def __init__(self, parent: Node, tf: WaitingTf):
        name = f"{parent.get_name()}_tf_listener"
        # The command line's remaps (/tf:=tf) apply; its __node:= would give both nodes one
        # name, so this node's own argument names it (local arguments come first).
        self.node = Node(name, namespace=parent.get_namespace(), context=parent.context,
                         cli_args=["--ros-args", "-r", f"__node:={name}"],
                         start_parameter_services=False)
        self.node.create_subscription(TFMessage, "/tf", tf.add_message, TF_QOS)
        self.node.create_subscription(TFMessage, "/tf_static",
                                      lambda m: tf.add_message(m, static=True), TF_STATIC_QOS)
        self.executor = SingleThreadedExecutor(context=parent.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, name="tf", daemon=True)
        self.thread.start()

    def _spin(self):
        try:
            self.executor.spin()
        except ExternalShutdownException:  # the context shut down: the node is stopping
            pass

    def shutdown(self):
        self.executor.shutdown(timeout_sec=1.0)
        self.thread.join(timeout=5)
        self.node.destroy_node()
