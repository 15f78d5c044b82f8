from setuptools import find_packages, setup

package_name = 'python_package_that_uses_the_messages'

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
    description='A publisher and a subscriber of the tutorial\'s AmazingQuote message.',
    license='MIT',
    entry_points={
        'console_scripts': [
            # TODO 2: register both executables, amazing_quote_publisher_node and
            #         amazing_quote_subscriber_node: 'NAME = PACKAGE.MODULE:FUNCTION'
        ],
    },
)
