"""Keeps the messages of subscribed topics for a rostest and waits for them with a hang guard
(never a timing assertion)."""
import threading

import rospy


class TopicStore:
    def __init__(self):
        self._lock = threading.Lock()
        self._messages = {}

    def subscribe(self, topic, msg_type, queue_size=5):
        """Keeps every message of `topic` from now on."""
        self._messages[topic] = []

        def keep(msg):
            with self._lock:
                self._messages[topic].append(msg)

        rospy.Subscriber(topic, msg_type, keep, queue_size=queue_size)

    def wait_for(self, topic, n=1, timeout_s=60):
        """The messages of `topic` once there are at least n; None after timeout_s."""
        deadline = rospy.Time.now() + rospy.Duration(timeout_s)
        while not rospy.is_shutdown() and rospy.Time.now() < deadline:
            with self._lock:
                if len(self._messages[topic]) >= n:
                    return list(self._messages[topic])
            rospy.sleep(0.05)
        return None
