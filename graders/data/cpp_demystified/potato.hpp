#pragma once
// The course's twin of the learner's include/cpp_demystified/potato.hpp: the same
// interface, plus counters of how each Potato was constructed. The grader puts it in
// place of the learner's copy (in a scratch folder) before compiling their
// src/demystified.cpp with harness.cpp.

namespace cpp_demystified
{

class Potato
{
public:
    /// How Potatoes were constructed since the last reset.
    struct Counts
    {
        int from_double = 0;
        int copies = 0;
        int moves = 0;
    };

    explicit Potato(const double& size) : size_(size) { ++counts().from_double; }
    Potato(const Potato& other) : size_(other.size_) { ++counts().copies; }
    Potato(Potato&& other) noexcept : size_(other.size_) { ++counts().moves; }
    Potato& operator=(const Potato& other)
    {
        size_ = other.size_;
        ++counts().copies;
        return *this;
    }
    Potato& operator=(Potato&& other) noexcept
    {
        size_ = other.size_;
        ++counts().moves;
        return *this;
    }
    ~Potato() = default;

    double size() const { return size_; }

    static Counts& counts()
    {
        static Counts c;
        return c;
    }

private:
    double size_;
};

}  // namespace cpp_demystified
