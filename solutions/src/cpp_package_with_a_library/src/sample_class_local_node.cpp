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
    RCLCPP_INFO_STREAM(get_logger(),
      "square_of_sum = " << std::to_string(SampleClass::square_of_sum(print_count_, print_count_ - 5)));
    RCLCPP_INFO_STREAM(get_logger(), sample_class_.to_string() << print_count_ << " times.");
    ++print_count_;
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
