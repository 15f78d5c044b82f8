// sample_class_local_node: every 0.5 s, logs a result of the library's SampleClass and the object itself.
#include <chrono>
#include <memory>
#include <string>

#include <rclcpp/rclcpp.hpp>

#include <cpp_package_with_a_library/sample_class.hpp>

class SampleClassLocalNode : public rclcpp::Node
{
public:
  SampleClassLocalNode()
  : rclcpp::Node("sample_class_local_node")
  {
    timer_ = create_wall_timer(std::chrono::milliseconds(500), [this]() {on_timer();});
  }

private:
  void on_timer()
  {
    // TODO 10: two records per tick, with RCLCPP_INFO_STREAM(get_logger(), ...):
    //   "square_of_sum = V", V being SampleClass::square_of_sum(print_count_, print_count_ - 5)
    //   sample_class_.to_string() followed by print_count_ and " times."
    // then count up.
  }

  SampleClass sample_class_;
  int print_count_{0};
  rclcpp::TimerBase::SharedPtr timer_;
};

int main(int argc, char ** argv)
{
  rclcpp::init(argc, argv);
  rclcpp::spin(std::make_shared<SampleClassLocalNode>());
  rclcpp::shutdown();
  return 0;
}
