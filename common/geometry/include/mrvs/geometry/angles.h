#pragma once
// Angle constants shared by the libraries (one definition instead of one per file).

namespace mrvs {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kRadToDeg = 180.0 / kPi;
inline constexpr double kDegToRad = kPi / 180.0;

}  // namespace mrvs
