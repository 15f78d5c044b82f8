from setuptools import find_packages, setup

package_name = 'python_package_with_a_library'

setup(
    name=package_name,
    version='0.0.1',
    # TODO: this installs only the top-level Python package, not its sub-package
    #       sample_python_library. List every package here (find_packages() can do it).
    packages=[package_name],
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A Python library other ROS 2 packages import: a function and a class.',
    license='MIT',
    entry_points={
        'console_scripts': [
        ],
    },
)
