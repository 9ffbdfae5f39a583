// Generates src/materials/ggx_albedo_table.h: the directional albedo E(mu, roughness) of a single-scattering
// GGX reflection lobe with Fresnel = 1, and its cosine-weighted average E_avg(roughness), used by the
// multiple-scattering compensation of Kulla & Conty 2017. Float64 tensor-product midpoint quadrature over the
// unit square of Heitz 2018 visible-normal sampling, where the integrand is G2/G1.
//
//   c++ -O2 -std=c++20 scripts/gen_ggx_albedo_table.cpp -o /tmp/gen
//   /tmp/gen > src/materials/ggx_albedo_table.h && clang-format -i src/materials/ggx_albedo_table.h
//   (/tmp/gen --check prints the bilinear interpolation error at cell centres instead)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace {

// Keep these in sync with ggx.h / ggx_albedo_table.h lookups.
constexpr int k_n_mu = 32;     // samples along x, mu = x^2 (dense near grazing, where E changes fastest)
constexpr int k_n_rough = 32;  // samples along perceptual roughness r, alpha = r^2
constexpr double k_min_alpha = 1e-3;
constexpr double k_min_mu = 1e-4;  // E at mu = 0 is the limit; evaluate just above it
constexpr int k_quad = 384;        // quadrature points per dimension

struct V3 {
    double x, y, z;
};
V3 norm(V3 v) {
    double l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return {v.x / l, v.y / l, v.z / l};
}

double lambda(double cos_t, double alpha) {
    double c2 = cos_t * cos_t;
    double tan2 = std::fmax(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + std::sqrt(1.0 + alpha * alpha * tan2));
}

// Directional albedo: E = integral over visible normals of G2(wo, wi) / G1(wo), wi = reflect(wo, wm).
double albedo(double mu, double alpha) {
    mu = std::fmax(mu, k_min_mu);
    V3 wo{std::sqrt(1.0 - mu * mu), 0.0, mu};
    double lo = lambda(mu, alpha);
    V3 vh = norm({alpha * wo.x, alpha * wo.y, wo.z});
    double lensq = vh.x * vh.x + vh.y * vh.y;
    V3 t1 = lensq > 0 ? V3{-vh.y / std::sqrt(lensq), vh.x / std::sqrt(lensq), 0} : V3{1, 0, 0};
    V3 t2{vh.y * t1.z - vh.z * t1.y, vh.z * t1.x - vh.x * t1.z, vh.x * t1.y - vh.y * t1.x};
    double sum = 0.0;
    for (int i = 0; i < k_quad; ++i) {
        // u1 = 1 - (1 - v)^3 resolves u1 -> 1, where the visible normals tilt to the horizon and the
        // reflected direction crosses it; the weight is the Jacobian du1/dv.
        double v = (i + 0.5) / k_quad;
        double u1 = 1.0 - std::pow(1.0 - v, 3.0);
        double jac = 3.0 * (1.0 - v) * (1.0 - v);
        double r = std::sqrt(u1);
        for (int j = 0; j < k_quad; ++j) {
            double phi = 2.0 * M_PI * (j + 0.5) / k_quad;
            double p1 = r * std::cos(phi), p2 = r * std::sin(phi);
            double s = 0.5 * (1.0 + vh.z);
            p2 = (1.0 - s) * std::sqrt(1.0 - p1 * p1) + s * p2;
            double pz = std::sqrt(std::fmax(0.0, 1.0 - p1 * p1 - p2 * p2));
            V3 nh{p1 * t1.x + p2 * t2.x + pz * vh.x, p1 * t1.y + p2 * t2.y + pz * vh.y,
                  p1 * t1.z + p2 * t2.z + pz * vh.z};
            V3 m = norm({alpha * nh.x, alpha * nh.y, std::fmax(0.0, nh.z)});
            double d = wo.x * m.x + wo.y * m.y + wo.z * m.z;
            double wiz = 2.0 * d * m.z - wo.z;
            if (wiz <= 0.0) continue;
            sum += jac * (1.0 + lo) / (1.0 + lo + lambda(wiz, alpha));
        }
    }
    return sum / (double(k_quad) * k_quad);
}

double mu_at(int i) { return std::pow(double(i) / (k_n_mu - 1), 2.0); }
double alpha_at(int j) { return std::fmax(std::pow(double(j) / (k_n_rough - 1), 2.0), k_min_alpha); }

double table[k_n_rough][k_n_mu];

// Piecewise-linear interpolant along x for one roughness row, as the runtime lookup does.
double lerp_row(int j, double mu) {
    double x = std::sqrt(mu) * (k_n_mu - 1);
    int i = std::min(int(x), k_n_mu - 2);
    double t = x - i;
    return table[j][i] * (1.0 - t) + table[j][i + 1] * t;
}

// E_avg = 2 * integral E(mu) mu dmu of the interpolant (not of the true E), so the compensation lobe built
// from the table integrates exactly to 1 - E(mu_o) of the table.
double average(int j) {
    const int n = 200000;
    double s = 0.0;
    for (int k = 0; k < n; ++k) {
        double mu = (k + 0.5) / n;
        s += lerp_row(j, mu) * mu;
    }
    return 2.0 * s / n;
}

}  // namespace

int main(int argc, char** argv) {
    bool check = argc > 1 && std::strcmp(argv[1], "--check") == 0;
    for (int j = 0; j < k_n_rough; ++j)
        for (int i = 0; i < k_n_mu; ++i) table[j][i] = albedo(mu_at(i), alpha_at(j));
    if (check) {
        double worst = 0.0;
        for (int j = 0; j < k_n_rough; ++j)
            for (int i = 0; i + 1 < k_n_mu; ++i) {
                double x = (i + 0.5) / (k_n_mu - 1);
                double mu = x * x;
                double err = std::fabs(albedo(mu, alpha_at(j)) - lerp_row(j, mu));
                if (err > worst && mu > 0.01 && j > 1) {
                    worst = err;
                    std::printf("r=%.3f mu=%.4f err=%.2e\n", std::sqrt(alpha_at(j)), mu, err);
                }
            }
        return 0;
    }
    std::printf(
        "// GENERATED by scripts/gen_ggx_albedo_table.cpp; do not edit. Regenerate with\n"
        "//   c++ -O2 -std=c++20 scripts/gen_ggx_albedo_table.cpp -o /tmp/gen\n"
        "//   /tmp/gen > src/materials/ggx_albedo_table.h   (about 15 s)\n"
        "//   clang-format -i src/materials/ggx_albedo_table.h\n"
        "// Directional albedo E(mu, r) of single-scattering GGX reflection with Fresnel = 1 "
        "(height-correlated\n"
        "// Smith G2), rows: perceptual roughness r = j / %d (alpha = max(r^2, %g)), columns: mu = (i / "
        "%d)^2;\n"
        "// E_avg(r) = 2 * integral of the row's piecewise-linear interpolant times mu. Float64 quadrature, "
        "%dx%d.\n"
        "#pragma once\n\n#include \"core/platform.h\"\n\nnamespace npt::materials {\n\n"
        "constexpr int k_ggx_table_n_mu = %d;\nconstexpr int k_ggx_table_n_rough = %d;\n\n",
        k_n_rough - 1, k_min_alpha, k_n_mu - 1, k_quad, k_quad, k_n_mu, k_n_rough);
    // nvcc cannot read a host constexpr array at a runtime index in device code, so the data is a macro that
    // defines a host copy and, under nvcc, a __device__ copy; ggx_albedo_entry picks the one for the caller.
    std::printf("// clang-format off\n#define NPT_GGX_ALBEDO_DATA { \\\n");
    for (int j = 0; j < k_n_rough; ++j) {
        std::printf("   ");
        for (int i = 0; i < k_n_mu; ++i) std::printf(" %.7ff,", table[j][i]);
        std::printf(" \\\n");
    }
    std::printf("}\n#define NPT_GGX_ALBEDO_AVG_DATA { \\\n   ");
    for (int j = 0; j < k_n_rough; ++j)
        std::printf(" %.7ff,%s", average(j), (j % 8 == 7 && j + 1 < k_n_rough) ? " \\\n   " : "");
    std::printf(" \\\n}\n// clang-format on\n\n");
    std::printf(
        "constexpr float k_ggx_albedo[k_ggx_table_n_rough * k_ggx_table_n_mu] = NPT_GGX_ALBEDO_DATA;\n"
        "constexpr float k_ggx_albedo_avg[k_ggx_table_n_rough] = NPT_GGX_ALBEDO_AVG_DATA;\n"
        "#if defined(__CUDACC__)\n"
        "__device__ constexpr float k_ggx_albedo_device[k_ggx_table_n_rough * k_ggx_table_n_mu] = "
        "NPT_GGX_ALBEDO_DATA;\n"
        "__device__ constexpr float k_ggx_albedo_avg_device[k_ggx_table_n_rough] = NPT_GGX_ALBEDO_AVG_DATA;\n"
        "#endif\n"
        "#undef NPT_GGX_ALBEDO_DATA\n#undef NPT_GGX_ALBEDO_AVG_DATA\n\n"
        "// E at row j (roughness), column i (mu); E_avg at row j.\n"
        "NPT_HD NPT_INLINE float ggx_albedo_entry(int j, int i) {\n"
        "#if defined(__CUDA_ARCH__)\n    return k_ggx_albedo_device[j * k_ggx_table_n_mu + i];\n"
        "#else\n    return k_ggx_albedo[j * k_ggx_table_n_mu + i];\n#endif\n}\n"
        "NPT_HD NPT_INLINE float ggx_albedo_avg_entry(int j) {\n"
        "#if defined(__CUDA_ARCH__)\n    return k_ggx_albedo_avg_device[j];\n"
        "#else\n    return k_ggx_albedo_avg[j];\n#endif\n}\n\n"
        "}  // namespace npt::materials\n");
    return 0;
}
