"""Protocol twins of the robot's devices: plain-Python servers of vendor protocols, no ROS.

ArduSub over MAVLink, the Water Linked DVL, the Reach Alpha 5 and the ATI Net F/T as their
vendors document them, the physics between them and the simulator (``plant_side``), the four
with that physics as one stand fed by calls (``twin_stand``), served either by the
``hardware_twins`` node over the simulator's ``/plant`` topics (``twins_node``) or inside the
simulator's own process (``simulator_with_twins``): the test stand of the bridges of
``uvms_hardware``. The robot's own computer installs the bridges, not these.
"""
