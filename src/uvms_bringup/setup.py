"""ament_python build of uvms_bringup."""

import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'uvms_bringup'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        (os.path.join('share', package_name, 'launch'), glob('launch/*.launch.py')),
        # The parameter files live at the repository top (config/); this package installs them.
        (os.path.join('share', package_name, 'config'),
         glob('../../config/*.yaml') + glob('../../config/*.xml')),
        (
            os.path.join('share', package_name, 'config', 'scenarios'),
            glob('../../config/scenarios/*.yaml'),
        ),
        (
            os.path.join('share', package_name, 'config', 'tasks'),
            glob('../../config/tasks/*.yaml'),
        ),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='UVMS developers',
    maintainer_email='dev@uvms.local',
    description=(
        'Bringup of the UVMS stack: the launch file, the configuration and scenarios, the '
        'in-process lockstep graph and the one-process-per-node launcher.'
    ),
    license='Apache-2.0',
)
