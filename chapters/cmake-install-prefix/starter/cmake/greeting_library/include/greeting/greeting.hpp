#pragma once

#include <string>

namespace greeting
{
/// Returns "Hello, <name>!".
std::string greet(const std::string& name);
}  // namespace greeting
