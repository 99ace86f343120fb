"""ament_python build of uvms_scenarios."""

from setuptools import find_packages, setup

package_name = 'uvms_scenarios'

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
        'The scenario file format of the UVMS stack: config/scenarios/*.yaml loaded and '
        'checked, each error naming its file and key (pure: no rclpy).'
    ),
    license='Apache-2.0',
)
