#include <iostream>

#include <greeting/greeting.hpp>

int main()
{
    std::cout << greeting::greet("prefix") << std::endl;
    return 0;
}
