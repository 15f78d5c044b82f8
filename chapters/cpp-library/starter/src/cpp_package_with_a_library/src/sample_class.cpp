#include <cpp_package_with_a_library/sample_class.hpp>

#include <sstream>

SampleClass::SampleClass()
: a_private_qt_string_("I am a QString"),
  a_private_eigen3_matrix_((Eigen::Matrix2d() << 1, 2, 3, 4).finished())
{
}

int SampleClass::get_a_private_member() const
{
  return a_private_member_;
}

void SampleClass::set_a_private_member(int value)
{
  a_private_member_ = value;
}

double SampleClass::square_of_sum(const double & a, const double & b)
{
  // TODO 9: return (a + b)^2, written out as a*a + 2*a*b + b*b
  (void)a;
  (void)b;
  return 0.0;
}

std::string SampleClass::to_string() const
{
  std::stringstream ss;
  ss << "Sample_Class:: " << std::endl
     << "a_private_member_ = " << a_private_member_ << std::endl
     << "a_private_qt_string_ = " << a_private_qt_string_.toStdString() << std::endl
     << "a_private_eigen3_matrix_ = " << a_private_eigen3_matrix_ << std::endl;
  return ss.str();
}

std::ostream & operator<<(std::ostream & os, const SampleClass & sc)
{
  return os << sc.to_string();
}
