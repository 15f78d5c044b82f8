// print_forever_node: logs "Printed N times." every 0.5 s, N counting up from 0.
#include <chrono>
#include <memory>

#include <rclcpp/rclcpp.hpp>

class PrintForeverNode : public rclcpp::Node
{
public:
  PrintForeverNode()
  : rclcpp::Node("TODO")  // TODO 3: the node's name is print_forever_node
  {
    // TODO 4: a wall timer that calls on_timer() every 500 ms; keep it in timer_
    //         (a timer nobody holds is destroyed at the end of the constructor)
  }

private:
  void on_timer()
  {
    // TODO 5: log "Printed N times." with RCLCPP_INFO (std::cout never reaches /rosout),
    //         N being print_count_, then count up
  }

  int print_count_{0};
  rclcpp::TimerBase::SharedPtr timer_;
};

int main(int argc, char ** argv)
{
  rclcpp::init(argc, argv);
  rclcpp::spin(std::make_shared<PrintForeverNode>());
  rclcpp::shutdown();
  return 0;
}
