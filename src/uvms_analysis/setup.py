"""ament_python build of uvms_analysis."""

from setuptools import find_packages, setup

package_name = 'uvms_analysis'

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
        "Offline analysis of UVMS recordings: series and metrics, the uvms report table "
        "and the paper's figures (pure: no rclpy)."
    ),
    license='Apache-2.0',
)
