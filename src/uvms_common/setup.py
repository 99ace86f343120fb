"""ament_python build of uvms_common."""

from setuptools import find_packages, setup

package_name = 'uvms_common'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    package_data={package_name: ['fastdds_loopback.xml']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=False,
    maintainer='UVMS developers',
    maintainer_email='dev@uvms.local',
    description=(
        'What every UVMS node process shares: the loopback-only DDS defaults and the node '
        'main loop (signal handling, executor choice, clean shutdown).'
    ),
    license='Apache-2.0',
)
