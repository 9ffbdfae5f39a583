#include "core/transform.h"

#include "core/error.h"

namespace npt {

Mat4 Mat4::translation(double x, double y, double z) {
    Mat4 r;
    r.m[0][3] = x;
    r.m[1][3] = y;
    r.m[2][3] = z;
    return r;
}

Mat4 Mat4::scale(double x, double y, double z) {
    Mat4 r;
    r.m[0][0] = x;
    r.m[1][1] = y;
    r.m[2][2] = z;
    return r;
}

Mat4 Mat4::rotation_quat(double x, double y, double z, double w) {
    double n = std::sqrt(x * x + y * y + z * z + w * w);
    if (n > 0) {
        x /= n;
        y /= n;
        z /= n;
        w /= n;
    }
    Mat4 r;
    r.m[0] = {1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w), 0};
    r.m[1] = {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w), 0};
    r.m[2] = {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y), 0};
    return r;
}

Mat4 Mat4::from_column_major(const double* v) {
    Mat4 r;
    for (int c = 0; c < 4; ++c)
        for (int row = 0; row < 4; ++row) r.m[row][c] = v[c * 4 + row];
    return r;
}

Mat4 Mat4::operator*(const Mat4& o) const {
    Mat4 r;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) {
            double s = 0;
            for (int k = 0; k < 4; ++k) s += m[i][k] * o.m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

Vec3 Mat4::transform_point(Vec3 p) const {
    double x = p.x, y = p.y, z = p.z;
    return {float(m[0][0] * x + m[0][1] * y + m[0][2] * z + m[0][3]),
            float(m[1][0] * x + m[1][1] * y + m[1][2] * z + m[1][3]),
            float(m[2][0] * x + m[2][1] * y + m[2][2] * z + m[2][3])};
}

Vec3 Mat4::transform_vector(Vec3 v) const {
    double x = v.x, y = v.y, z = v.z;
    return {float(m[0][0] * x + m[0][1] * y + m[0][2] * z), float(m[1][0] * x + m[1][1] * y + m[1][2] * z),
            float(m[2][0] * x + m[2][1] * y + m[2][2] * z)};
}

Vec3 Mat4::transform_normal(Vec3 n) const {
    Mat4 inv = inverse();
    double x = n.x, y = n.y, z = n.z;
    // (M^-1)^T n
    return {float(inv.m[0][0] * x + inv.m[1][0] * y + inv.m[2][0] * z),
            float(inv.m[0][1] * x + inv.m[1][1] * y + inv.m[2][1] * z),
            float(inv.m[0][2] * x + inv.m[1][2] * y + inv.m[2][2] * z)};
}

double Mat4::determinant3() const {
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Mat4 Mat4::inverse() const {
    // Affine inverse: [A t]^-1 = [A^-1, -A^-1 t].
    double det = determinant3();
    if (!std::isfinite(det) || std::fabs(det) < 1e-300) throw Error("transform is singular (zero scale?)");
    double id = 1.0 / det;
    Mat4 r;
    r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) * id;
    r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * id;
    r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * id;
    r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) * id;
    r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * id;
    r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * id;
    r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) * id;
    r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * id;
    r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * id;
    for (int i = 0; i < 3; ++i)
        r.m[i][3] = -(r.m[i][0] * m[0][3] + r.m[i][1] * m[1][3] + r.m[i][2] * m[2][3]);
    return r;
}

bool Mat4::is_finite() const {
    for (auto& row : m)
        for (double v : row)
            if (!std::isfinite(v)) return false;
    return true;
}

}  // namespace npt
