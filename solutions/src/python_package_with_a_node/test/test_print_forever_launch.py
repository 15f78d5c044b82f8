"""An integration test: launch print_forever_node, judge what it logs, then how it exits.

`colcon test` runs it with pytest; launch_testing's pytest plugin starts the launch
description, runs the first class while the node runs, shuts the launch down (Ctrl+C
to the node) and runs the post-shutdown class.
"""

import re
import unittest

import launch
import launch_ros.actions
import launch_testing.actions
import launch_testing.asserts
import pytest

#: One record as rclpy writes it to standard error: '[INFO] [1732450000.123456789] [print_forever_node]: Printed 0 times.'
RECORD = re.compile(r'\[(\d+\.\d+)\] \[[^\]]*\]: Printed (\d+) times\.')


@pytest.mark.launch_test
def generate_test_description():
    node = launch_ros.actions.Node(package='python_package_with_a_node', executable='print_forever_node')
    return launch.LaunchDescription([node, launch_testing.actions.ReadyToTest()]), {'node': node}


class TestWhileItRuns(unittest.TestCase):

    def test_it_counts_from_zero_twice_a_second(self, proc_output, node):
        proc_output.assertWaitFor('Printed 4 times.', process=node, timeout=10.0)
        text = ''.join(event.text.decode() for event in proc_output[node])
        records = [(float(stamp), int(count)) for stamp, count in RECORD.findall(text)]
        # from zero, one at a time
        self.assertEqual([count for _, count in records[:5]], [0, 1, 2, 3, 4])
        # four periods of 0.5 s between the first and the fifth record, timed by the node's own
        # stamps (not by when this test read them: a loaded machine delays the reading, not the stamps)
        self.assertAlmostEqual(records[4][0] - records[0][0], 2.0, delta=0.25)


@launch_testing.post_shutdown_test()
class TestAfterShutdown(unittest.TestCase):

    def test_it_exits_cleanly_on_ctrl_c(self, proc_info, node):
        launch_testing.asserts.assertExitCodes(proc_info, process=node)
