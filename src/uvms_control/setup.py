"""ament_python build of uvms_control."""

from setuptools import find_packages, setup

package_name = 'uvms_control'

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
        'Unified force controller (impedance + hybrid position/force, fuzzy switching) and '
        'thruster allocation with thruster dynamics, as pure cores and ROS 2 nodes.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'controller = uvms_control.entry_points:controller',
            'thruster_allocator = uvms_control.entry_points:thruster_allocator',
        ],
    },
)
