"""ament_python build of uvms_sweep."""

from setuptools import find_packages, setup

package_name = 'uvms_sweep'

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
        'Parameter sweeps of UVMS scenarios on Ray: sweep files, the engine, the point '
        'runner, the table and the metric maps.'
    ),
    license='Apache-2.0',
)
