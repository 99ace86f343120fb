"""ament_python build of uvms_recording."""

from setuptools import find_packages, setup

package_name = 'uvms_recording'

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
        'Recording and replay of the UVMS graph: the recorder node, the MCAP writer and '
        'reader (rosbag2 layout), the message typestore, replay and the controller re-run.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'recorder = uvms_recording.entry_points:recorder',
        ],
    },
)
