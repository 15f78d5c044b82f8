// The course's test harness for the lesson cpp-demystified (graders/cpp_demystified.py).
// Compiled in one g++ call with the learner's src/demystified.cpp, -O0 -D_GLIBCXX_ASSERTIONS
// (so operator[] past the end aborts instead of reading garbage), against the counting
// potato.hpp. Run once per test: `harness at|try|acos|potato`; it prints one line,
// "PASS <what it saw>" or "FAIL <what it saw>", and exits 0 (an abort or a crash means the
// learner's code ended the program).

#include <cxxabi.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <new>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cpp_demystified/demystified.hpp"

using cpp_demystified::Potato;

// --- heap allocations, counted (std::make_shared makes one; shared_ptr(new T) makes two) ---
static long g_allocations = 0;

void* operator new(std::size_t n)
{
    ++g_allocations;
    if (void* p = std::malloc(n ? n : 1))
    {
        return p;
    }
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace
{

/// The demangled type of the exception being handled (inside a catch block).
std::string current_exception_type()
{
    std::type_info* type = abi::__cxa_current_exception_type();
    if (type == nullptr)
    {
        return "an unknown exception";
    }
    int status = 0;
    char* name = abi::__cxa_demangle(type->name(), nullptr, nullptr, &status);
    std::string result = (status == 0 && name != nullptr) ? name : type->name();
    std::free(name);
    return result;
}

std::string number(double x)
{
    char buffer[64];  // the shortest of 15 or 17 digits that reads back as x
    std::snprintf(buffer, sizeof buffer, "%.15g", x);
    if (std::strtod(buffer, nullptr) != x && !std::isnan(x))
    {
        std::snprintf(buffer, sizeof buffer, "%.17g", x);
    }
    return buffer;
}

std::string describe(const std::optional<double>& value)
{
    return value ? "a value holding " + number(*value) : std::string("std::nullopt");
}

int verdict(bool ok, const std::string& observed)
{
    std::printf("%s %s\n", ok ? "PASS" : "FAIL", observed.c_str());
    std::fflush(stdout);
    return 0;
}

const std::vector<double> kValues{1.0, 2.0, 3.0, 4.0};

int test_at()
{
    using cpp_demystified::checked_element;
    const double second = checked_element(kValues, 1);
    if (second != 2.0)
    {
        return verdict(false, "checked_element({1, 2, 3, 4}, 1) returned " + number(second) + " instead of 2");
    }
    for (std::size_t index : {std::size_t{4}, std::size_t{22}})
    {
        const std::string call = "checked_element({1, 2, 3, 4}, " + std::to_string(index) + ")";
        try
        {
            const double got = checked_element(kValues, index);
            return verdict(false, call + " returned " + number(got) + " without throwing");
        }
        catch (const std::out_of_range&)
        {
        }
        catch (const std::exception& e)
        {
            return verdict(false, call + " threw " + current_exception_type() + " (" + e.what() +
                                      ") instead of std::out_of_range");
        }
        catch (...)
        {
            return verdict(false, call + " threw " + current_exception_type() + " instead of std::out_of_range");
        }
    }
    return verdict(true, "index 1 gives 2; indices 4 and 22 throw std::out_of_range");
}

int test_try()
{
    using cpp_demystified::try_element;
    std::string call = "try_element({1, 2, 3, 4}, 2)";
    try
    {
        const auto third = try_element(kValues, 2);
        if (!third || *third != 3.0)
        {
            return verdict(false, call + " returned " + describe(third) + " instead of 3");
        }
        for (std::size_t index : {std::size_t{4}, std::size_t{22}})
        {
            call = "try_element({1, 2, 3, 4}, " + std::to_string(index) + ")";
            const auto got = try_element(kValues, index);
            if (got)
            {
                return verdict(false, call + " returned " + describe(got) + " instead of std::nullopt");
            }
        }
    }
    catch (...)
    {
        return verdict(false, current_exception_type() + " escaped from " + call +
                                  ": your catch does not match the exception .at() throws");
    }
    return verdict(true, "index 2 gives 3; indices 4 and 22 give std::nullopt, nothing escapes");
}

int test_acos()
{
    using cpp_demystified::safe_acos;
    const double half = std::acos(0.5);
    struct Case
    {
        double x;
        bool valid;
    };
    // NaN itself too: acos(NaN) is NaN, which only the lesson's std::isnan test of the result catches (a range
    // check of x lets it through; the independent review of stop 82 got full marks with one)
    for (const Case& c : {Case{0.5, true}, Case{1.0, true}, Case{1.1, false}, Case{-1.1, false},
                          Case{std::numeric_limits<double>::quiet_NaN(), false}})
    {
        const std::string call = "safe_acos(" + number(c.x) + ")";
        std::optional<double> got;
        try
        {
            got = safe_acos(c.x);
        }
        catch (...)
        {
            return verdict(false, call + " threw " + current_exception_type() +
                                      " (std::acos throws nothing: it returns NaN)");
        }
        if (c.valid)
        {
            const double want = c.x == 0.5 ? half : 0.0;
            if (!got || std::fabs(*got - want) > 1e-12)
            {
                return verdict(false, call + " returned " + describe(got) + " instead of " + number(want));
            }
        }
        else if (got)
        {
            return verdict(false, call + " returned " + describe(got) + " instead of std::nullopt" +
                                      (std::isnan(*got) ? ": the NaN was not detected" : ""));
        }
    }
    return verdict(true, "0.5 and 1.0 give their acos; 1.1, -1.1 and NaN give std::nullopt");
}

int test_potato()
{
    Potato::counts() = Potato::Counts{};
    const long before = g_allocations;
    std::shared_ptr<Potato> potato = cpp_demystified::make_potato(20.0);
    const long allocations = g_allocations - before;
    const Potato::Counts counts = Potato::counts();
    if (!potato)
    {
        return verdict(false, "make_potato(20.0) returned an empty shared_ptr");
    }
    const std::string seen = std::to_string(counts.from_double) + " Potato(s) built from a double, " +
                             std::to_string(counts.copies) + " copy(ies), " + std::to_string(counts.moves) +
                             " move(s), " + std::to_string(allocations) + " heap allocation(s)";
    if (potato->size() != 20.0)
    {
        return verdict(false, "make_potato(20.0)->size() is " + number(potato->size()) + " (" + seen + ")");
    }
    const bool ok = counts.from_double == 1 && counts.copies == 0 && counts.moves == 0 && allocations == 1;
    return verdict(ok, "make_potato(20.0): " + seen);
}

}  // namespace

int main(int argc, char** argv)
{
    const std::string test = argc > 1 ? argv[1] : "";
    try
    {
        if (test == "at") return test_at();
        if (test == "try") return test_try();
        if (test == "acos") return test_acos();
        if (test == "potato") return test_potato();
    }
    catch (const std::exception& e)
    {
        return verdict(false, current_exception_type() + " (" + e.what() + ") escaped from your function");
    }
    catch (...)
    {
        return verdict(false, current_exception_type() + " escaped from your function");
    }
    std::fprintf(stderr, "usage: harness at|try|acos|potato\n");
    return 2;
}
