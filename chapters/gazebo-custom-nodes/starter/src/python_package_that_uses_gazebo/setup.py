from glob import glob

from setuptools import find_packages, setup

package_name = 'python_package_that_uses_gazebo'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # TODO 2: install launch/*_launch.py into share/<package>/launch and config_bridge/*.yaml into
        #         share/<package>/config_bridge (glob is imported above)
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='Three nodes that move a box in a Gazebo world.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO 3: register send_poses_to_gazebo_node, send_wrenches_to_gazebo_node and control_shape_thrust_node
            #         ('<executable> = python_package_that_uses_gazebo.<module>:main')
        ],
    },
)
