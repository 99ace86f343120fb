"""ament_python build of uvms_thrusters."""

import runpy
from pathlib import Path

from setuptools import find_packages, setup

package_name = 'uvms_thrusters'
#: The kernel-compiling install and develop commands, shared by the packages with kernels
#: (loaded by path: setup.py runs before any package of the repository is importable).
KERNEL_SETUP = Path(__file__).resolve().parents[2] / 'tools' / 'kernel_setup.py'
kernel_commands = runpy.run_path(str(KERNEL_SETUP))['kernel_commands']


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
        'Thruster allocation (eq. 10), Healey thruster dynamics (eq. 11-15) and their kernels, '
        'fault injection and detection, and the thruster_allocator node.'
    ),
    license='Apache-2.0',
    cmdclass=kernel_commands(package_name, Path(__file__).resolve().parent),
    entry_points={
        'console_scripts': [
            'thruster_allocator = uvms_thrusters.entry_points:thruster_allocator',
        ],
    },
)
