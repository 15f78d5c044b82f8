#include "cpp_demystified/demystified.hpp"

#include <cmath>
#include <stdexcept>

namespace cpp_demystified
{

double checked_element(const std::vector<double>& values, std::size_t index)
{
    return values.at(index);
}

std::optional<double> try_element(const std::vector<double>& values, std::size_t index)
{
    try
    {
        return values.at(index);
    }
    catch (const std::out_of_range&)
    {
        return std::nullopt;
    }
}

std::optional<double> safe_acos(double x)
{
    const double angle = std::acos(x);
    if (std::isnan(angle))
    {
        return std::nullopt;
    }
    return angle;
}

std::shared_ptr<Potato> make_potato(double size)
{
    return std::make_shared<Potato>(size);
}

}  // namespace cpp_demystified
