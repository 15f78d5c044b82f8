// The myrobot driver: a sas::RobotDriver subclass (seed ch. 31.5). No driver internals in this header.
#pragma once
#include <atomic>
#include <memory>
#include <string>
#include <tuple>
#include <sas_core/sas_robot_driver.hpp>

namespace sas
{

struct RobotDriverMyrobotConfiguration
{
    std::string ip;
    std::tuple<Eigen::VectorXd, Eigen::VectorXd> joint_limits;  // radians
};

class RobotDriverMyrobot : public RobotDriver
{
    RobotDriverMyrobotConfiguration configuration_;
    class Impl;  // PIMPL: the robot's own library stays out of this header
    std::unique_ptr<Impl> impl_;

public:
    RobotDriverMyrobot(const RobotDriverMyrobot&) = delete;
    RobotDriverMyrobot() = delete;
    RobotDriverMyrobot(const RobotDriverMyrobotConfiguration& configuration, std::atomic_bool* break_loops);
    ~RobotDriverMyrobot();

    Eigen::VectorXd get_joint_positions() override;
    void set_target_joint_positions(const Eigen::VectorXd& desired_joint_positions_rad) override;
    void connect() override;
    void disconnect() override;
    void initialize() override;
    void deinitialize() override;
};

}  // namespace sas
