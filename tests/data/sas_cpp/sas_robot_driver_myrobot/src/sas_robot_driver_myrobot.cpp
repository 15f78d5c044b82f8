// A simulated myrobot: a target becomes the joint positions at once (seed ch. 31.5).
#include "sas_robot_driver_myrobot/sas_robot_driver_myrobot.hpp"
#include <stdexcept>

namespace sas
{

class RobotDriverMyrobot::Impl
{
public:
    bool connected{false};
    bool motor_on{false};
    Eigen::VectorXd joint_positions;  // size 0 = not valid
};

RobotDriverMyrobot::RobotDriverMyrobot(const RobotDriverMyrobotConfiguration& configuration,
                                       std::atomic_bool* break_loops)
    : RobotDriver(break_loops), configuration_(configuration), impl_(std::make_unique<Impl>())
{
    joint_limits_ = configuration.joint_limits;  // the superclass publishes these
}

RobotDriverMyrobot::~RobotDriverMyrobot() = default;

Eigen::VectorXd RobotDriverMyrobot::get_joint_positions()
{
    if (impl_->joint_positions.size() == 0)
        throw std::runtime_error("Tried to obtain invalid joint positions");
    return impl_->joint_positions;
}

void RobotDriverMyrobot::set_target_joint_positions(const Eigen::VectorXd& desired_joint_positions_rad)
{
    if (desired_joint_positions_rad.size() != 6)
        throw std::runtime_error("Incorrect vector size in RobotDriverMyrobot::set_target_joint_positions");
    impl_->joint_positions = desired_joint_positions_rad;
}

void RobotDriverMyrobot::connect()
{
    if (impl_->connected)
        throw std::runtime_error("Already connected.");
    impl_->connected = true;
    impl_->motor_on = false;
    impl_->joint_positions = Eigen::VectorXd::Zero(6);
}

void RobotDriverMyrobot::initialize()
{
    if (!impl_->connected)
        throw std::runtime_error("Not connected.");
    impl_->motor_on = true;
}

void RobotDriverMyrobot::deinitialize()  // must not throw
{
    impl_->motor_on = false;
}

void RobotDriverMyrobot::disconnect()  // must not throw
{
    impl_->connected = false;
    impl_->joint_positions = Eigen::VectorXd();
}

}  // namespace sas
