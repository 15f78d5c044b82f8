from setuptools import find_packages, setup

package_name = 'python_package_that_uses_qos'

setup(
    name=package_name,
    version='0.0.1',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A sensor stream, a latched configuration and a monitor that receives both: QoS profiles.',
    license='MIT',
    entry_points={
        'console_scripts': [
            'sensor_publisher_node = python_package_that_uses_qos.sensor_publisher_node:main',
            'config_publisher_node = python_package_that_uses_qos.config_publisher_node:main',
            'sensor_monitor_node = python_package_that_uses_qos.sensor_monitor_node:main',
        ],
    },
)
