"""ament_python build of uvms_pilot."""

from setuptools import find_packages, setup

package_name = 'uvms_pilot'

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
        'uvms pilot: a person drives the vehicle and the arm from a terminal UI or a gamepad '
        "onto the controller's pilot topics."
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
        ],
    },
)
