from setuptools import find_packages, setup

package_name = 'python_package_with_a_library'

setup(
    name=package_name,
    version='0.0.1',
    # find_packages() lists the package *and* its sub-package sample_python_library;
    # packages=[package_name] would install only the top level (seed ch. 14.6).
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    tests_require=['pytest'],
    maintainer='ros2course learner',
    maintainer_email='learner@example.com',
    description='A Python library other ROS 2 packages import: a function and a class.',
    license='MIT',
    entry_points={
        'console_scripts': [
        ],
    },
)
