// The myrobot node (seed ch. 31.6): parameters in, sas::RobotDriverROS does the ROS side.
#include <atomic>
#include <csignal>
#include <stdexcept>
#include <rclcpp/rclcpp.hpp>
#include <sas_common/sas_common.hpp>
#include <sas_core/eigen3_std_conversions.hpp>
#include <sas_robot_driver/sas_robot_driver_ros.hpp>
#include <sas_robot_driver_myrobot/sas_robot_driver_myrobot.hpp>
#include <dqrobotics/utils/DQ_Math.h>

static std::atomic_bool kill_this_process(false);
static void sig_int_handler(int) { kill_this_process = true; }

int main(int argc, char** argv)
{
    if (std::signal(SIGINT, sig_int_handler) == SIG_ERR)
        throw std::runtime_error("Error setting the SIGINT handler.");
    rclcpp::init(argc, argv, rclcpp::InitOptions(), rclcpp::SignalHandlerOptions::None);
    auto node = std::make_shared<rclcpp::Node>("sas_robot_driver_myrobot");
    try
    {
        sas::RobotDriverMyrobotConfiguration configuration;
        sas::get_ros_parameter(node, "ip", configuration.ip);
        std::vector<double> limits_min, limits_max;
        sas::get_ros_parameter(node, "joint_limits_min", limits_min);
        sas::get_ros_parameter(node, "joint_limits_max", limits_max);
        configuration.joint_limits = {DQ_robotics::deg2rad(sas::std_vector_double_to_vectorxd(limits_min)),
                                      DQ_robotics::deg2rad(sas::std_vector_double_to_vectorxd(limits_max))};

        sas::RobotDriverROSConfiguration ros_configuration;
        sas::get_ros_parameter(node, "thread_sampling_time_sec", ros_configuration.thread_sampling_time_sec);
        ros_configuration.robot_driver_provider_prefix = node->get_name();

        auto driver = std::make_shared<sas::RobotDriverMyrobot>(configuration, &kill_this_process);
        sas::RobotDriverROS robot_driver_ros(node, driver, ros_configuration, &kill_this_process);
        robot_driver_ros.control_loop();
    }
    catch (const std::exception& e)
    {
        RCLCPP_ERROR_STREAM_ONCE(node->get_logger(), std::string("::Exception::") + e.what());
    }
    return 0;
}
