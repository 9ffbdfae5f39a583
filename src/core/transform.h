// 4x4 affine transforms in double precision, for loaders and placement (host side; not per sample).
#pragma once

#include <array>
#include <cmath>

#include "core/vec.h"

namespace npt {

struct Mat4 {
    // Row-major: m[row][col]; points are column vectors, p' = M p.
    std::array<std::array<double, 4>, 4> m{{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};

    static Mat4 identity() { return {}; }
    static Mat4 translation(double x, double y, double z);
    static Mat4 scale(double x, double y, double z);
    // Unit quaternion (x, y, z, w), glTF order.
    static Mat4 rotation_quat(double x, double y, double z, double w);
    // From 16 numbers in column-major order (glTF `matrix`).
    static Mat4 from_column_major(const double* v);

    Mat4 operator*(const Mat4& o) const;
    Vec3 transform_point(Vec3 p) const;
    Vec3 transform_vector(Vec3 v) const;
    // Normals transform by the inverse transpose of the linear part.
    Vec3 transform_normal(Vec3 n) const;
    Mat4 inverse() const;  // throws npt::Error when singular
    double determinant3() const;  // of the upper-left 3x3; negative means the transform mirrors
    bool is_finite() const;
};

}  // namespace npt
