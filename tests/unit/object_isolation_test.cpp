#include "nerf/object_isolation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "core/error.h"

namespace npt::nerf {
namespace {

constexpr int k_res = 32;

Vec3 centre_of(int64_t i) {
    const float h = 1.0f / k_res;
    return {(float(i % k_res) + 0.5f) * h, (float((i / k_res) % k_res) + 0.5f) * h,
            (float(i / (k_res * k_res)) + 0.5f) * h};
}

// One cascade of 32^3 cells; `inside(p)` (model space) says which cells hold density 1 (else 0).
std::vector<float> grid_of(const std::function<bool(Vec3)>& inside) {
    std::vector<float> d(size_t(k_res) * k_res * k_res, 0.0f);
    for (size_t i = 0; i < d.size(); ++i) d[i] = inside(centre_of(int64_t(i))) ? 1.0f : 0.0f;
    return d;
}

float dist(Vec3 a, Vec3 b) {
    return std::sqrt((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y) + (a.z - b.z) * (a.z - b.z));
}

bool in_blob(Vec3 p) { return dist(p, {0.5f, 0.5f, 0.5f}) < 0.1f; }
bool in_floater(Vec3 p) {
    return dist(p, {8.5f / 32, 23.5f / 32, 21.5f / 32}) < 0.04f;
}  // 7 cells (a cross), in the box
// The table top: one layer of cells wholly under the plane z = 0.3 (a layer straddling the plane stays in the
// grid, and the renderer cuts it: CellsStraddlingThePlaneOrTheBoxStay).
bool in_slab(Vec3 p) { return p.z > 0.25f && p.z < 0.28f; }
bool in_prop(Vec3 p) { return dist(p, {0.9f, 0.9f, 0.45f}) < 0.06f; }  // outside the box

// Object space: the plane z = 0.3 of the model is z = 0, the box +-0.3 around x = y = 0.5, 0.5 high.
IsolationInput input() {
    IsolationInput in;
    in.cascades = 1;
    in.resolution = k_res;
    in.model_to_object = Mat4::translation(-0.5, -0.5, -0.3);
    in.box_min = {-0.3f, -0.3f, 0.0f};
    in.box_max = {0.3f, 0.3f, 0.5f};
    return in;
}

TEST(ObjectIsolation, OnlyTheBlobRemainsOfBlobFloaterSlabAndProp) {
    std::vector<float> d =
        grid_of([](Vec3 p) { return in_blob(p) || in_floater(p) || in_slab(p) || in_prop(p); });
    int64_t blob = 0, floater = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        blob += in_blob(centre_of(int64_t(i)));
        floater += in_floater(centre_of(int64_t(i)));
    }
    ASSERT_GT(floater, 0);
    ASSERT_LT(floater, IsolationSettings{}.min_component_cells);
    const IsolationStats st = isolate_object(d, input(), IsolationSettings{});
    for (size_t i = 0; i < d.size(); ++i) EXPECT_EQ(d[i] > 0, in_blob(centre_of(int64_t(i)))) << "cell " << i;
    EXPECT_EQ(st.occupied_after, blob);
    EXPECT_EQ(st.cut_as_floaters, floater);
    EXPECT_EQ(st.kept_components, 1);
}

TEST(ObjectIsolation, AllOfABlobAloneIsKept) {
    std::vector<float> d = grid_of(in_blob);
    const std::vector<float> before = d;
    const IsolationStats st = isolate_object(d, input(), IsolationSettings{});
    EXPECT_EQ(d, before);
    EXPECT_EQ(st.cut_by_region + st.cut_as_floaters, 0);
}

TEST(ObjectIsolation, ASecondPartAsLargeAsTheThresholdIsKept) {
    // A second blob of 2x2x2 cells (8, the threshold) apart from the first: a real part, kept.
    const auto second = [](Vec3 p) {
        return p.x > 0.75f && p.x < 0.8125f && p.y > 0.5f && p.y < 0.5625f && p.z > 0.5f && p.z < 0.5625f;
    };
    std::vector<float> d = grid_of([&](Vec3 p) { return in_blob(p) || second(p); });
    const IsolationStats st = isolate_object(d, input(), IsolationSettings{});
    EXPECT_EQ(st.kept_components, 2);
    EXPECT_EQ(st.cut_as_floaters, 0);
}

TEST(ObjectIsolation, UpNeedNotBeTheModelsZ) {
    // The same scene turned so that up is the model's +y: object (x, y, z) = model (x - 0.5, z - 0.5, y -
    // 0.3).
    std::vector<float> d = grid_of([](Vec3 p) {
        const Vec3 q{p.x, p.z, p.y};
        return in_blob(q) || in_slab(q) || in_prop(q);
    });
    IsolationInput in = input();
    Mat4 m;
    m.m = {{{1, 0, 0, -0.5}, {0, 0, 1, -0.5}, {0, 1, 0, -0.3}, {0, 0, 0, 1}}};
    in.model_to_object = m;
    isolate_object(d, in, IsolationSettings{});
    for (size_t i = 0; i < d.size(); ++i) {
        const Vec3 p = centre_of(int64_t(i));
        EXPECT_EQ(d[i] > 0, in_blob({p.x, p.z, p.y})) << "cell " << i;
    }
}

TEST(ObjectIsolation, CellsBelowThePlaneMarginGoEvenInsideTheBox) {
    // A column from the slab up into the blob: connected to the blob, but the cells that lie wholly under
    // plane + margin go; those straddling that height stay (the renderer cuts there exactly).
    std::vector<float> d = grid_of([](Vec3 p) {
        return in_blob(p) ||
               (std::fabs(p.x - 0.5f) < 0.03f && std::fabs(p.y - 0.5f) < 0.03f && p.z > 0.2f && p.z < 0.5f);
    });
    IsolationSettings settings;
    settings.plane_margin_cells = 1.0;
    isolate_object(d, input(), settings);
    const float cell = 1.0f / k_res;
    int straddling = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        const Vec3 p = centre_of(int64_t(i));
        const bool column = std::fabs(p.x - 0.5f) < 0.03f && std::fabs(p.y - 0.5f) < 0.03f && p.z > 0.2f;
        if (p.z + 0.5f * cell < 0.3f + cell) {
            EXPECT_EQ(d[i], 0.0f) << "cell " << i;
        } else if (column && p.z - 0.5f * cell < 0.3f + cell) {
            EXPECT_GT(d[i], 0.0f) << "straddling cell " << i;
            ++straddling;
        }
    }
    EXPECT_GT(straddling, 0);
}

TEST(ObjectIsolation, CellsStraddlingThePlaneOrTheBoxStay) {
    // An object standing on the plane (z = 0.3) whose base reaches into the cells that straddle the plane, and
    // whose side reaches into a cell whose centre lies past the box's face (object x = 0.3, model x = 0.8):
    // nothing of it is cut by the region.
    const auto standing = [](Vec3 p) {
        return std::fabs(p.x - 0.63f) < 0.19f && std::fabs(p.y - 0.5f) < 0.05f && p.z > 0.29f && p.z < 0.45f;
    };
    std::vector<float> d = grid_of(standing);
    const std::vector<float> before = d;
    const IsolationStats st = isolate_object(d, input(), IsolationSettings{});
    EXPECT_EQ(st.cut_by_region, 0);
    EXPECT_EQ(d, before);
}

// The table's density reaching above the plane (a slab 1.5 cells thick across the whole box) under a cylinder
// standing on it: the table layer keeps only what lies under the cylinder's footprint.
float axis_distance(Vec3 p) { return std::hypot(p.x - 0.5f, p.y - 0.5f); }
bool in_table_layer(Vec3 p) { return p.z > 0.29f && p.z < 0.34f; }  // cells 9 and 10: object z -0.1 .. 0.9 cells
bool in_cylinder(Vec3 p) { return axis_distance(p) < 0.1f && p.z > 0.29f && p.z < 0.6f; }
// Cells that overlap the box's sides (input(): +-0.3 around x = y = 0.5): the region the plane and box keep.
bool in_box_columns(Vec3 p) {
    const float reach = 0.3f + 0.5f / k_res;
    return std::fabs(p.x - 0.5f) < reach && std::fabs(p.y - 0.5f) < reach;
}

TEST(ObjectIsolation, TheTableLayerKeepsOnlyTheObjectsFootprint) {
    const float cell = 1.0f / k_res;
    IsolationInput in = input();
    in.min_step = 1.0f / (2.0f * k_res);  // density 1: opacity 1 - e^-2 = 0.86 across a cell, dense
    std::vector<float> d = grid_of([](Vec3 p) { return in_table_layer(p) || in_cylinder(p); });
    IsolationSettings s;  // a layer of 2 cells (the slab's geometry is laid out for it), footprint + 1 cell
    s.table_layer_cells = 2.0;
    ASSERT_EQ(s.footprint_margin_cells, 1.0);
    const IsolationStats st = isolate_object(d, in, s);
    int64_t cut = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        const Vec3 p = centre_of(int64_t(i));
        if (in_cylinder(p)) EXPECT_GT(d[i], 0) << "cylinder cell " << i << " cut";
        // Beyond the footprint's reach (1 cell of margin, half a cell for the marking cell's extent, and the
        // footprint raster's rounding of both cells' centres, 2 x sqrt(2) / 4 = 0.71 cell at most), no table is
        // left: 0.1 (the cylinder's outermost centres lie within it) + 2.25 cells.
        if (in_table_layer(p) && axis_distance(p) > 0.1f + 2.25f * cell) EXPECT_EQ(d[i], 0) << "table cell " << i;
        cut += in_table_layer(p) && !in_cylinder(p) && in_box_columns(p) && d[i] == 0;
    }
    EXPECT_GT(cut, 100);
    EXPECT_EQ(st.cut_off_footprint, cut);

    // Without the layer (or without a dense cell above it) the plane alone cuts: the whole slab stays.
    IsolationSettings off = s;
    off.table_layer_cells = 0;
    std::vector<float> d_off = grid_of([](Vec3 p) { return in_table_layer(p) || in_cylinder(p); });
    EXPECT_EQ(isolate_object(d_off, in, off).cut_off_footprint, 0);
    std::vector<float> slab_only = grid_of(in_table_layer);
    EXPECT_EQ(isolate_object(slab_only, in, s).cut_off_footprint, 0);
    for (size_t i = 0; i < slab_only.size(); ++i)
        if (in_table_layer(centre_of(int64_t(i))) && in_box_columns(centre_of(int64_t(i))))
            EXPECT_GT(slab_only[i], 0) << "table cell " << i << " cut with no footprint above it";
}

// A mushroom on the table: a stem (radius 0.06) under a cap (radius 0.2) from 6 cells above the layer. The
// footprint is the foot's (the dense cells within 4 cells of the lowest above the layer): the table under the
// cap's overhang goes. Taken from every dense cell above the layer (slab 0, the first rule) it stays.
bool in_stem(Vec3 p) { return axis_distance(p) < 0.06f && p.z > 0.29f && p.z < 0.55f; }
bool in_cap(Vec3 p) { return axis_distance(p) < 0.2f && p.z > 0.55f && p.z < 0.65f; }

TEST(ObjectIsolation, TheFootprintIsTheFootsNotTheOverhangs) {
    const float cell = 1.0f / k_res;
    IsolationInput in = input();
    in.min_step = 1.0f / (2.0f * k_res);  // density 1: dense
    const auto mushroom = [](Vec3 p) { return in_table_layer(p) || in_stem(p) || in_cap(p); };
    std::vector<float> d = grid_of(mushroom);
    IsolationSettings s;
    s.table_layer_cells = 2.0;  // the cap is 6 cells above this layer
    ASSERT_EQ(s.footprint_slab_cells, 4.0);
    isolate_object(d, in, s);
    int64_t under_cap = 0, kept_under_cap = 0;
    for (size_t i = 0; i < d.size(); ++i) {
        const Vec3 p = centre_of(int64_t(i));
        if (in_stem(p) || in_cap(p)) EXPECT_GT(d[i], 0) << "mushroom cell " << i << " cut";
        // Under the cap, beyond the stem's footprint and its reach (as in the test above: 2.25 cells).
        if (in_table_layer(p) && !in_stem(p) && axis_distance(p) > 0.06f + 2.25f * cell &&
            axis_distance(p) < 0.2f) {
            ++under_cap;
            kept_under_cap += d[i] > 0;
        }
    }
    EXPECT_GT(under_cap, 50);
    EXPECT_EQ(kept_under_cap, 0);

    IsolationSettings all_above = s;
    all_above.footprint_slab_cells = 0;
    std::vector<float> d_all = grid_of(mushroom);
    isolate_object(d_all, in, all_above);
    for (size_t i = 0; i < d_all.size(); ++i) {
        const Vec3 p = centre_of(int64_t(i));
        if (in_table_layer(p) && axis_distance(p) < 0.2f - 0.5f * cell)
            EXPECT_GT(d_all[i], 0) << "cell " << i;
    }
}

TEST(ObjectIsolation, RefusesAGridOfTheWrongSize) {
    std::vector<float> d(100, 1.0f);
    EXPECT_THROW(isolate_object(d, input(), IsolationSettings{}), Error);
}

}  // namespace
}  // namespace npt::nerf

namespace npt::nerf {
namespace {

TEST(ObjectIsolation, AModelWithoutAnObjectFrameIsRefusedNamingTheFile) {
    NerfModel m;
    try {
        isolate_model(m, IsolationSettings{}, "cap/model.npt");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("cap/model.npt: the model has no object frame"),
                  std::string::npos);
    }
}

}  // namespace
}  // namespace npt::nerf
