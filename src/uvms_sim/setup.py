"""ament_python build of uvms_sim."""

from setuptools import find_packages, setup

package_name = 'uvms_sim'

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
        'Simulator node of the UVMS: integrates the uvms_model plant with the wall '
        'contact and the wrist force/torque sensor, publishes the robot state.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'simulator = uvms_sim.entry_points:simulator',
        ],
    },
)
