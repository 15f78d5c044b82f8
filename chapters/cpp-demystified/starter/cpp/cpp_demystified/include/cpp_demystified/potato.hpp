#pragma once

namespace cpp_demystified
{

/// A potato of a given size. Do not change this file: `ros2course check`
/// swaps it for a copy with the same interface that counts copies and moves.
class Potato
{
public:
    explicit Potato(const double& size) : size_(size) {}

    double size() const { return size_; }

private:
    double size_;
};

}  // namespace cpp_demystified
