// The seed's C++ print_forever_node (ch. 26): logs "Printed N times." every 0.5 s.
#include <chrono>
#include <memory>

#include <rclcpp/rclcpp.hpp>

using namespace std::chrono_literals;

class PrintForeverNode : public rclcpp::Node
{
public:
  PrintForeverNode()
  : rclcpp::Node("print_forever_node")
  {
    timer_ = create_wall_timer(500ms, [this]() {
        RCLCPP_INFO(get_logger(), "Printed %d times.", print_count_);
        print_count_++;
      });
  }

private:
  rclcpp::TimerBase::SharedPtr timer_;
  int print_count_ = 0;
};

int main(int argc, char ** argv)
{
  rclcpp::init(argc, argv);
  rclcpp::spin(std::make_shared<PrintForeverNode>());
  rclcpp::shutdown();
  return 0;
}
