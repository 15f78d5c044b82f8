#include <cmath>
#include <iostream>
#include <stdexcept>
#include <vector>

#include "cpp_demystified/demystified.hpp"

using namespace cpp_demystified;

int main()
{
    // Bounds-checked access: .at() throws instead of reading past the end.
    std::vector<double> values{1.0, 2.0, 3.0, 4.0};
    try
    {
        std::cout << values.at(22) << std::endl;
    }
    catch (const std::out_of_range& e)
    {
        std::cout << "out of range: " << e.what() << std::endl;
    }
    std::cout << "try_element(values, 22) has a value: " << std::boolalpha
              << try_element(values, 22).has_value() << std::endl;

    // acos(1.1) throws nothing: it returns NaN, which only std::isnan detects.
    const double a = std::acos(1.1);
    if (std::isnan(a))
    {
        std::cout << "acos(1.1) is NaN: the input was invalid" << std::endl;
    }
    else
    {
        std::cout << "acos(1.1) = " << a << std::endl;
    }

    // make_shared forwards 20.0 to Potato's constructor: one Potato, no copy.
    const auto potato = make_potato(20.0);
    std::cout << "potato size: " << potato->size() << std::endl;
    return 0;
}
