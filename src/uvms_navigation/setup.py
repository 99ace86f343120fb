"""ament_python build of uvms_navigation."""

from setuptools import find_packages, setup

package_name = 'uvms_navigation'

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
        'Navigation of the UVMS: the estimator node fusing IMU, DVL, depth and position '
        'fixes, and its pure error-state EKF core.'
    ),
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'estimator = uvms_navigation.entry_points:estimator',
        ],
    },
)
