// Mathematical constants: M_PI is POSIX, not ISO C++, and bare-metal newlib in strict C++17
// mode does not define it.
#pragma once

namespace hmpc {

template <typename Scalar>
constexpr Scalar kPi = Scalar(3.14159265358979323846264338327950288);

}  // namespace hmpc
