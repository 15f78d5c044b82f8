#include <cmath>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "cpp_demystified/demystified.hpp"

using namespace cpp_demystified;

int main()
{
    // TODO 1: make a std::vector<double> of four values, print .at(22) inside a try block
    //         and print e.what() of the std::out_of_range you catch.

    // TODO 2: compute std::acos(1.1) and print whether std::isnan says it is NaN.

    // TODO 3: print the size of make_potato(20.0).

    std::cout << "demo not written yet" << std::endl;
    return 0;
}
