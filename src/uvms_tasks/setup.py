"""ament_python build of uvms_tasks."""

from setuptools import find_packages, setup

package_name = 'uvms_tasks'

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
        'Commanding the controller: task and mission files, ContactTask goals, a client for '
        'scripts, the mission node and uvms task.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'mission = uvms_tasks.entry_points:mission',
        ],
    },
)
