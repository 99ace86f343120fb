"""ament_python build of uvms_hardware."""

from setuptools import find_packages, setup

package_name = 'uvms_hardware'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # The autopilot's side of the thruster watchdog, copied to ArduSub's scripts folder
        # by hand (docs/hardware.md); ardusub_watchdog.script_path finds it here.
        ('share/' + package_name + '/autopilot', ['autopilot/uvms_thruster_watchdog.lua']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='UVMS developers',
    maintainer_email='dev@uvms.local',
    description=(
        "Bridges from the UVMS graph to the robot's own protocols (ArduSub over MAVLink, "
        'Water Linked DVL, Reach Alpha serial protocol, ATI Net F/T) and their pure protocol '
        'codecs (the twins to test them against: uvms_twins).'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'alpha5_bridge = uvms_hardware.entry_points:alpha5_bridge',
            'netft_bridge = uvms_hardware.entry_points:netft_bridge',
            'ardusub_bridge = uvms_hardware.entry_points:ardusub_bridge',
            'dvl_bridge = uvms_hardware.entry_points:dvl_bridge',
        ],
    },
)
