#include "cpp_demystified/demystified.hpp"

#include <cmath>
#include <stdexcept>

namespace cpp_demystified
{

double checked_element(const std::vector<double>& values, std::size_t index)
{
    // TODO: return the element at `index`; past the end it must throw std::out_of_range.
    (void)values;
    (void)index;
    throw std::logic_error("checked_element is not written yet");
}

std::optional<double> try_element(const std::vector<double>& values, std::size_t index)
{
    // TODO: the element at `index`, or std::nullopt when .at() throws std::out_of_range.
    (void)values;
    (void)index;
    return std::nullopt;
}

std::optional<double> safe_acos(double x)
{
    // TODO: std::acos(x), or std::nullopt when the result is NaN.
    (void)x;
    return std::nullopt;
}

std::shared_ptr<Potato> make_potato(double size)
{
    // TODO: a shared Potato of this size, constructed once, with no temporary Potato.
    (void)size;
    return nullptr;
}

}  // namespace cpp_demystified
