"""Bridges from the UVMS graph to the robot's own protocols, and their codecs.

ArduSub over MAVLink, Water Linked DVL, the Reach Alpha serial protocol and ATI Net F/T: pure
protocol codecs and device cores, and the ROS 2 bridge nodes on one base (``bridge_node``).
The protocol twins to test them against are a package of their own, ``uvms_twins``: the
robot's computer installs the bridges, not the twins.
"""
