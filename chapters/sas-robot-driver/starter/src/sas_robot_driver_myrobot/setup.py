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
        # TODO: install launch/real_robot_launch.py into share/<package>/launch,
        #       where `ros2 launch sas_robot_driver_myrobot real_robot_launch.py` looks for it.
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A Python driver for myrobot with the SmartArmStack RobotDriverROS interface, and a client.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO: the driver node, sas_robot_driver_myrobot_node
            # TODO: the client, joint_interface_example
        ],
    },
)
