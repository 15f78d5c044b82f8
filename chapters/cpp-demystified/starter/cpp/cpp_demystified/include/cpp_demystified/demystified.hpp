#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "cpp_demystified/potato.hpp"

namespace cpp_demystified
{

/// values[index], bounds-checked: throws std::out_of_range when index >= values.size().
double checked_element(const std::vector<double>& values, std::size_t index);

/// values[index], or std::nullopt when index is out of range (std::out_of_range caught inside).
std::optional<double> try_element(const std::vector<double>& values, std::size_t index);

/// acos(x) in radians, or std::nullopt when the result is NaN (|x| > 1, or x is NaN).
std::optional<double> safe_acos(double x);

/// A shared Potato of the given size, constructed once, in place.
std::shared_ptr<Potato> make_potato(double size);

}  // namespace cpp_demystified
