// The small types of the core: 3-vectors, 3x3 matrices and rigid poses (Eigen, double precision).
// Frames are named in the monogram style: X_WB is the pose of frame B in frame W, p_WC a point C in W.
#pragma once

#include <Eigen/Geometry>

namespace implicit_sim {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Pose = Eigen::Isometry3d;

constexpr double kPi = 3.14159265358979323846;

}  // namespace implicit_sim
