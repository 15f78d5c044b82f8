#include <greeting/greeting.hpp>

namespace greeting
{
std::string greet(const std::string& name)
{
    return "Hello, " + name + "!";
}
}  // namespace greeting
