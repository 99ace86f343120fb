"""ament_python build of uvms_run."""

from setuptools import find_packages, setup

package_name = 'uvms_run'

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
        'The whole UVMS node graph in one process (uvms run): built from the parameter '
        'files and a scenario, run in lockstep or real time, with its progress bars.'
    ),
    license='Apache-2.0',
)
