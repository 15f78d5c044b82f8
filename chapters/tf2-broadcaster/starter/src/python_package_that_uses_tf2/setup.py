from setuptools import find_packages, setup

package_name = 'python_package_that_uses_tf2'

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
    description='A robot frame moving on a circle and a camera fixed on it: tf2 broadcasters.',
    license='MIT',
    entry_points={
        'console_scripts': [
            'circle_broadcaster = python_package_that_uses_tf2.circle_broadcaster:main',
        ],
    },
)
