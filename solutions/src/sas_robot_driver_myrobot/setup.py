import os
from glob import glob

from setuptools import find_packages, setup

package_name = 'sas_robot_driver_myrobot'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # `ros2 launch sas_robot_driver_myrobot real_robot_launch.py` looks in share/<package>/launch
        (os.path.join('share', package_name, 'launch'), glob(os.path.join('launch', '*launch.[pxy][yma]*'))),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A Python driver for myrobot with the SmartArmStack RobotDriverROS interface, and a client.',
    license='MIT',
    entry_points={
        'console_scripts': [
            'sas_robot_driver_myrobot_node = sas_robot_driver_myrobot.sas_robot_driver_myrobot_node:main',
            'joint_interface_example = sas_robot_driver_myrobot.joint_interface_example:main',
        ],
    },
)
