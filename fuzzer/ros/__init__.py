"""Real ROS 1 (Debian 12's Noetic core from apt): master, nodes, topics, tf2, bags, RViz (issue 13).

``env`` imports Debian's ROS Python packages into the project's interpreter;
``processes`` starts the master and nodes as process groups that die with the
engine; ``node`` makes this process a rospy node; ``transport`` runs targets as
ROS nodes (``--transport ros``); ``bags`` reads seeds from and writes
divergences to rosbag files; ``view`` shows a divergence in RViz. The ``ros_tf``
target lives in ``adapters/ros_tf.py``. Nothing here is imported by the
in-process engine unless a ROS feature is used.
"""
