#pragma once

#include <ostream>
#include <string>

#include <QString>
#include <Eigen/Dense>

/// A class that does very little, but with an Eigen3 and a Qt member: users of the library need both.
class SampleClass
{
private:
  int a_private_member_;  // TODO 8: give it a starting value of 0 (the tutorial never initialises it)
  const QString a_private_qt_string_;
  const Eigen::MatrixXd a_private_eigen3_matrix_;

public:
  SampleClass();

  int get_a_private_member() const;
  void set_a_private_member(int value);
  std::string to_string() const;

  /// (a + b)^2, i.e. a*a + 2*a*b + b*b.
  static double square_of_sum(const double & a, const double & b);
};

std::ostream & operator<<(std::ostream & os, const SampleClass & sc);
