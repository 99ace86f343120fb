"""Bridges from the UVMS graph to the robot's own protocols, their codecs and twins.

ArduSub over MAVLink, Water Linked DVL, the Reach Alpha serial protocol and ATI Net F/T: pure
protocol codecs, ROS 2 bridge nodes, and protocol twins to test them against.
"""
