#pragma once
// Two-view geometry of the calibrated stereo pair used by the front-end's stereo checks.
// Frames: c0 left camera, c1 right camera; T_c1_c0 maps left-camera points into the right.
// xn are undistorted normalised coordinates (x / z, y / z).
#include <optional>

#include "mrvs/geometry/se3.h"
#include "mrvs/geometry/types.h"

namespace mrvs::edge {

/// Distance of xn1 to the epipolar line of xn0 in the right image, in normalised units
/// (multiply by the right camera's focal length for pixels). The line is E * [xn0; 1] with
/// E = [p_c1_c0]x R_c1_c0.
double epipolar_distance(const SE3d& T_c1_c0, const Vec2d& xn0, const Vec2d& xn1);

/// Depths (z in c0, z in c1) of the point closest to both rays (midpoint of the common
/// perpendicular); nullopt when the rays are parallel within 1e-12.
std::optional<Vec2d> triangulate_depths(const SE3d& T_c1_c0, const Vec2d& xn0, const Vec2d& xn1);

}  // namespace mrvs::edge
