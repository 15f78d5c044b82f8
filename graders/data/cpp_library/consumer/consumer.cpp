// The grader's use of the learner's SampleClass (ros2course cpp-library): prints key=value lines
// that graders/cpp_library.py compares with what the chapter's class does.
#include <cpp_package_with_a_library/sample_class.hpp>

#include <cstddef>
#include <iostream>
#include <new>
#include <sstream>

int main()
{
  std::cout.precision(17);
  std::cout << "square_of_sum(2,3)=" << SampleClass::square_of_sum(2.0, 3.0) << "\n";
  std::cout << "square_of_sum(-1.5,0.25)=" << SampleClass::square_of_sum(-1.5, 0.25) << "\n";

  // Build the object on storage full of garbage: a member the constructor forgets to
  // initialise then shows that garbage instead of 0, every time.
  alignas(SampleClass) unsigned char storage[sizeof(SampleClass)];
  volatile unsigned char * bytes = storage;
  for (std::size_t i = 0; i < sizeof(SampleClass); ++i) {
    bytes[i] = 0x5A;
  }
  SampleClass * sample = new (storage) SampleClass();
  std::cout << "initial_member=" << sample->get_a_private_member() << "\n";
  const std::string text = sample->to_string();
  sample->set_a_private_member(42);
  std::cout << "member_after_set=" << sample->get_a_private_member() << "\n";
  std::ostringstream streamed;
  streamed << *sample;
  std::cout << "stream_matches_to_string=" << (streamed.str() == sample->to_string() ? "yes" : "no") << "\n";
  sample->~SampleClass();
  std::cout << "to_string:\n" << text;
  return 0;
}
