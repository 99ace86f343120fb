"""ament_python build of uvms_viz."""

from setuptools import find_packages, setup

package_name = 'uvms_viz'

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
        'Viewing the UVMS: the visualizer node (markers for the wall, the contact force and '
        'the path) and the Foxglove live view node.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'visualizer = uvms_viz.entry_points:visualizer',
            'foxglove_server = uvms_viz.entry_points:foxglove_server',
        ],
    },
)
