"""An integration test of print_forever_node with launch_testing.

`colcon test` runs it with pytest: launch_testing's plugin starts the launch
description, runs the test classes while the node runs, shuts the launch down
(Ctrl+C to the node), then runs the classes marked post_shutdown_test.
"""

import unittest

import launch
import launch_ros.actions
import launch_testing.actions
import pytest


@pytest.mark.launch_test
def generate_test_description():
    node = launch_ros.actions.Node(package='python_package_with_a_node', executable='print_forever_node')
    return launch.LaunchDescription([node, launch_testing.actions.ReadyToTest()]), {'node': node}


class TestWhileItRuns(unittest.TestCase):

    def test_it_logs(self, proc_output, node):
        # TODO: wait for what the node must log, e.g.
        #       proc_output.assertWaitFor('Printed 0 times.', process=node, timeout=10.0)
        #       and judge the order and the timing of the records.
        pass


# TODO: a class marked @launch_testing.post_shutdown_test() whose test checks the node's exit code
#       with launch_testing.asserts.assertExitCodes(proc_info, process=node).
