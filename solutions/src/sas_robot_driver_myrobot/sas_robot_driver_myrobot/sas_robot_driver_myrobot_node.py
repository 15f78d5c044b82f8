"""The driver node of myrobot (seed ch. 31.6, in Python).

Reads its parameters (limits in degrees, converted to radians), creates the
driver and runs the sas control loop until Ctrl+C, then turns the robot off
and disconnects.
"""

import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.parameter import Parameter

from sas_robot_driver_myrobot.robot_driver_myrobot import RobotDriverMyrobot, RobotDriverMyrobotConfiguration
from sas_robot_driver_myrobot.robot_driver_ros import RobotDriverROS, RobotDriverROSConfiguration


def get_ros_parameter(node: Node, name: str, parameter_type: Parameter.Type):
    """Declare and read a parameter that must be given (like ``sas::get_ros_parameter``)."""
    node.declare_parameter(name, parameter_type)
    value = node.get_parameter(name).value
    if value is None:
        raise RuntimeError(f'The parameter {name} was not set.')
    return value


def main(args=None):
    rclpy.init(args=args)
    node = Node('sas_robot_driver_myrobot')
    logger = node.get_logger()
    robot_driver = None
    try:
        logger.info('::Loading parameters from the parameter server.')
        ip = get_ros_parameter(node, 'ip', Parameter.Type.STRING)
        joint_limits_min = get_ros_parameter(node, 'joint_limits_min', Parameter.Type.DOUBLE_ARRAY)
        joint_limits_max = get_ros_parameter(node, 'joint_limits_max', Parameter.Type.DOUBLE_ARRAY)
        configuration = RobotDriverMyrobotConfiguration(
            ip=ip, joint_limits=(np.deg2rad(np.array(joint_limits_min)), np.deg2rad(np.array(joint_limits_max))))
        ros_configuration = RobotDriverROSConfiguration(
            thread_sampling_time_sec=get_ros_parameter(node, 'thread_sampling_time_sec', Parameter.Type.DOUBLE),
            robot_driver_provider_prefix=node.get_name())
        logger.info('::Parameters OK.')

        logger.info('::Instantiating RobotDriverMyrobot.')
        robot_driver = RobotDriverMyrobot(configuration)
        logger.info('::Instantiating RobotDriverROS.')
        robot_driver_ros = RobotDriverROS(node, robot_driver, ros_configuration)
        robot_driver_ros.control_loop()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception as e:  # a driver error ends the node cleanly, as sas does
        logger.error(f'::Exception::{e}')
    finally:
        if robot_driver is not None:
            robot_driver.deinitialize()
            robot_driver.disconnect()
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
