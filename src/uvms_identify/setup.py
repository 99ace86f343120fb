"""ament_python build of uvms_identify."""

from setuptools import find_packages, setup

package_name = 'uvms_identify'

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
        "uvms identify: the vehicle's hydrodynamics (added mass, damping, buoyancy) from "
        'its own recordings, by constrained least squares.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
        ],
    },
)
