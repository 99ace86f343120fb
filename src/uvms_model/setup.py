"""ament_python build of uvms_model."""

from setuptools import find_packages, setup

package_name = 'uvms_model'

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
        'Pure numpy/scipy model of the underwater vehicle-manipulator system: kinematics,'
        ' dynamics, hydrodynamics, contact, sensors, thruster layout (paper sections 3 '
        'and 5.1).'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
        ],
    },
)
