// Internal contract checks: VDISO_CHECK_EQ(a, b) etc. print both operands and abort.
// They guard invariants of our own code, never untrusted input (that gets an exception).
// Compiled out when VDISO_NO_CHECKS is defined.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace vdiso::detail {

template <class A, class B>
[[noreturn]] void checkFailed(const char* expr, const A& a, const B& b, const char* file, int line) {
    std::ostringstream os;
    os << a << " vs " << b;
    std::fprintf(stderr, "%s:%d: check failed: %s (%s)\n", file, line, expr, os.str().c_str());
    std::abort();
}

}  // namespace vdiso::detail

#ifdef VDISO_NO_CHECKS
#define VDISO_CHECK_OP(a, op, b) ((void)0)
#else
#define VDISO_CHECK_OP(a, op, b)                                                      \
    do {                                                                              \
        const auto& vdisoA_ = (a);                                                    \
        const auto& vdisoB_ = (b);                                                    \
        if (!(vdisoA_ op vdisoB_))                                                    \
            ::vdiso::detail::checkFailed(#a " " #op " " #b, vdisoA_, vdisoB_, __FILE__, \
                                         __LINE__);                                   \
    } while (0)
#endif

#define VDISO_CHECK_EQ(a, b) VDISO_CHECK_OP(a, ==, b)
#define VDISO_CHECK_LT(a, b) VDISO_CHECK_OP(a, <, b)
#define VDISO_CHECK_LE(a, b) VDISO_CHECK_OP(a, <=, b)
#define VDISO_CHECK(cond) VDISO_CHECK_OP(bool(cond), ==, true)
