from setuptools import find_packages, setup

package_name = 'python_package_with_a_node'

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
    description='Python nodes of the ros2course tutorial.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO: register the executable sample_python_node.
            #       The form is 'EXECUTABLE = PYTHON_PACKAGE.MODULE:FUNCTION'
        ],
    },
)
