// print_forever_node: logs "Printed N times." every 0.5 s, N counting up from 0.
#include <chrono>
#include <memory>

#include <rclcpp/rclcpp.hpp>

class PrintForeverNode : public rclcpp::Node
{
public:
  PrintForeverNode()
  : rclcpp::Node("print_forever_node")
  {
    // the executor calls on_timer() every period; no loop, no sleep
    timer_ = create_wall_timer(std::chrono::milliseconds(500), [this]() {on_timer();});
  }

private:
  void on_timer()
  {
    // RCLCPP_INFO goes to the terminal and to /rosout
    RCLCPP_INFO(get_logger(), "Printed %d times.", print_count_);
    ++print_count_;
  }

  int print_count_{0};
  rclcpp::TimerBase::SharedPtr timer_;
};

int main(int argc, char ** argv)
{
  rclcpp::init(argc, argv);
  // rclcpp::init installs a SIGINT handler: Ctrl+C shuts the context down and spin() returns
  rclcpp::spin(std::make_shared<PrintForeverNode>());
  rclcpp::shutdown();
  return 0;
}
