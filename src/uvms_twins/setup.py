"""ament_python build of uvms_twins."""

from setuptools import find_packages, setup

package_name = 'uvms_twins'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='UVMS developers',
    maintainer_email='dev@uvms.local',
    description=(
        "Protocol twins of the robot's devices (ArduSub over MAVLink, Water Linked DVL, "
        'Reach Alpha 5, ATI Net F/T) and the hardware_twins node that serves them on the '
        'simulator: the test stand of the uvms_hardware bridges.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'hardware_twins = uvms_twins.entry_points:hardware_twins',
            'simulator_with_twins = uvms_twins.entry_points:simulator_with_twins',
        ],
    },
)
