"""Protocol twins of the robot's devices: plain-Python servers of vendor protocols, no ROS.

ArduSub over MAVLink, the Water Linked DVL, the Reach Alpha 5 and the ATI Net F/T as their
vendors document them, the physics between them and the simulator (``plant_side``), and the
``hardware_twins`` node that serves them on the simulator (``twins_node``): the test stand of
the bridges of ``uvms_hardware``. The robot's own computer installs the bridges, not these.
"""
