#include "nerf/object_isolation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "core/error.h"
#include "nerf/occupancy_grid.h"

namespace npt::nerf {

namespace {

Vec3 row_of(const Mat4& m, size_t r) { return {float(m.m[r][0]), float(m.m[r][1]), float(m.m[r][2])}; }

// Centre of cell (x, y, z) of cascade 0 in object space.
Vec3 object_centre(const IsolationInput& in, int64_t x, int64_t y, int64_t z) {
    const float h = 1.0f / float(in.resolution);
    return in.model_to_object.transform_point(
        Vec3{(float(x) + 0.5f) * h, (float(y) + 0.5f) * h, (float(z) + 0.5f) * h});
}

// The table-layer rule (IsolationSettings::table_layer_cells): cells of cascade 0 in the region whose centre
// lies below the layer leave it unless they lie under the object's footprint. Returns the occupied cells cut.
int64_t cut_table_layer(const std::vector<float>& density, float occupied_threshold, const IsolationInput& in,
                        const IsolationSettings& s, float cell0, const Vec3& extent, std::vector<uint8_t>& in_region) {
    const int64_t R = in.resolution;
    const float layer = float(s.table_layer_cells) * cell0;
    // The footprint on a raster of half a cell over the box (plus the margin), in object x and y; a point goes
    // to its nearest raster node, at most sqrt(2) / 4 of a cell away.
    const float spacing = 0.5f * cell0;
    const float margin = float(s.footprint_margin_cells) * cell0;
    const float x0 = in.box_min.x - margin - cell0, y0 = in.box_min.y - margin - cell0;
    const int64_t nx = int64_t(std::ceil((in.box_max.x - in.box_min.x + 2 * (margin + cell0)) / spacing)) + 1;
    const int64_t ny = int64_t(std::ceil((in.box_max.y - in.box_min.y + 2 * (margin + cell0)) / spacing)) + 1;
    if (nx <= 0 || ny <= 0 || nx * ny > (int64_t(1) << 26)) return 0;
    const auto pixel = [&](const Vec3& o, int64_t& px, int64_t& py) {
        px = int64_t(std::lround((o.x - x0) / spacing));
        py = int64_t(std::lround((o.y - y0) / spacing));
        return px >= 0 && py >= 0 && px < nx && py < ny;
    };
    const float dense =
        float(occupancy_density_for_opacity(std::min(s.footprint_opacity, 0.999), 1.0, int(R), in.min_step));
    // The dense cells above the layer; with a slab, only those within it of the lowest one (the object's
    // foot).
    const auto dense_above = [&](size_t i, const Vec3& o) {
        return in_region[i] && density[i] >= dense && density[i] > occupied_threshold && o.z >= layer;
    };
    float lowest = std::numeric_limits<float>::infinity();
    for (int64_t z = 0; z < R; ++z)
        for (int64_t y = 0; y < R; ++y)
            for (int64_t x = 0; x < R; ++x) {
                const Vec3 o = object_centre(in, x, y, z);
                if (dense_above(size_t(x + y * R + z * R * R), o)) lowest = std::min(lowest, o.z);
            }
    // Nothing dense above the layer: the rule has no footprint to keep, so it cuts nothing.
    if (!std::isfinite(lowest)) return 0;
    const float top = s.footprint_slab_cells > 0 ? lowest + float(s.footprint_slab_cells) * cell0
                                                 : std::numeric_limits<float>::infinity();
    std::vector<uint8_t> marked(size_t(nx * ny), 0);
    bool any = false;
    for (int64_t z = 0; z < R; ++z)
        for (int64_t y = 0; y < R; ++y)
            for (int64_t x = 0; x < R; ++x) {
                const Vec3 o = object_centre(in, x, y, z);
                int64_t px, py;
                if (!dense_above(size_t(x + y * R + z * R * R), o) || o.z > top || !pixel(o, px, py))
                    continue;
                marked[size_t(px + py * nx)] = 1;
                any = true;
            }
    if (!any) return 0;
    // Widened by the margin plus the half extent of a cell (a cell centre marks its whole cell).
    const float reach = margin + 0.5f * std::max(extent.x, extent.y) * (1.0f / float(R));
    const int64_t r = int64_t(std::ceil(reach / spacing));
    std::vector<uint8_t> under(marked.size(), 0);
    for (int64_t py = 0; py < ny; ++py)
        for (int64_t px = 0; px < nx; ++px) {
            if (!marked[size_t(px + py * nx)]) continue;
            for (int64_t dy = -r; dy <= r; ++dy)
                for (int64_t dx = -r; dx <= r; ++dx) {
                    const int64_t qx = px + dx, qy = py + dy;
                    if (qx < 0 || qy < 0 || qx >= nx || qy >= ny) continue;
                    if (float(dx * dx + dy * dy) * spacing * spacing > reach * reach) continue;
                    under[size_t(qx + qy * nx)] = 1;
                }
        }
    int64_t cut = 0;
    for (int64_t z = 0; z < R; ++z)
        for (int64_t y = 0; y < R; ++y)
            for (int64_t x = 0; x < R; ++x) {
                const size_t i = size_t(x + y * R + z * R * R);
                if (!in_region[i]) continue;
                const Vec3 o = object_centre(in, x, y, z);
                if (o.z >= layer) continue;
                int64_t px, py;
                if (pixel(o, px, py) && under[size_t(px + py * nx)]) continue;
                in_region[i] = 0;
                cut += density[i] > occupied_threshold;
            }
    return cut;
}

}  // namespace

IsolationStats isolate_object(std::vector<float>& density, const IsolationInput& in,
                              const IsolationSettings& s) {
    const int64_t R = in.resolution;
    const int64_t per_cascade = R * R * R;
    if (in.cascades < 1 || R < 1 || int64_t(density.size()) != int64_t(in.cascades) * per_cascade)
        throw Error("isolate_object: the occupancy grid holds " + std::to_string(density.size()) +
                    " cells, not cascades x resolution^3 = " + std::to_string(in.cascades) + " x " +
                    std::to_string(R) + "^3");
    if (s.plane_margin_cells < 0 || s.min_component_cells < 1)
        throw Error("isolate_object: plane margin must be >= 0 cells and the component size >= 1 cell");

    double sum = 0;
    for (float d : density) sum += double(d);
    const float mean = float(sum / double(density.size()));
    const float threshold = std::min(in.occupied_threshold, mean);

    // Object space: z is the height above the plane. A model-space cell of side h spans, along object axis a,
    // h * (|ra0| + |ra1| + |ra2|) (row a of the map).
    Vec3 extent;
    for (int a = 0; a < 3; ++a) {
        const Vec3 r = row_of(in.model_to_object, a);
        extent[a] = std::fabs(r.x) + std::fabs(r.y) + std::fabs(r.z);
    }
    const float object_per_model = std::sqrt(float(in.model_to_object.m[0][0] * in.model_to_object.m[0][0] +
                                                   in.model_to_object.m[1][0] * in.model_to_object.m[1][0] +
                                                   in.model_to_object.m[2][0] * in.model_to_object.m[2][0]));
    const float cell0 = object_per_model / float(R);  // a cascade-0 cell's side in object units
    const float z_floor = float(s.plane_margin_cells) * cell0;

    IsolationStats st;
    std::vector<uint8_t> in_region(density.size(), 0);
    for (int c = 0; c < in.cascades; ++c) {
        const float size = float(1 << c);
        const float lo = 0.5f - 0.5f * size;
        const float h = size / float(R);
        for (int64_t z = 0; z < R; ++z)
            for (int64_t y = 0; y < R; ++y)
                for (int64_t x = 0; x < R; ++x) {
                    const size_t i = size_t(int64_t(c) * per_cascade + x + y * R + z * R * R);
                    const bool occupied = density[i] > threshold;
                    st.occupied_before += occupied;
                    const Vec3 centre{lo + (float(x) + 0.5f) * h, lo + (float(y) + 0.5f) * h,
                                      lo + (float(z) + 0.5f) * h};
                    const Vec3 o = in.model_to_object.transform_point(centre);
                    // Cells that overlap the region stay (their bounding extent in object space): the exact
                    // cut at the box's faces and the plane is the renderer's (the model is marked
                    // object_only), so no part of the object's base or sides is lost with a straddling cell.
                    const Vec3 half = extent * (0.5f * h);
                    const bool inside = o.z + half.z >= z_floor && o.x + half.x >= in.box_min.x &&
                                        o.x - half.x <= in.box_max.x && o.y + half.y >= in.box_min.y &&
                                        o.y - half.y <= in.box_max.y && o.z - half.z <= in.box_max.z;
                    in_region[i] = inside;
                    if (occupied && !inside) ++st.cut_by_region;
                }
    }

    if (s.table_layer_cells > 0 && in.min_step > 0)
        st.cut_off_footprint = cut_table_layer(density, threshold, in, s, cell0, extent, in_region);

    // 26-connected components of the occupied cells of cascade 0 inside the region (flood fill with a stack).
    std::vector<int32_t> label(size_t(per_cascade), -1);
    std::vector<int64_t> sizes;
    std::vector<int64_t> stack;
    for (int64_t i = 0; i < per_cascade; ++i) {
        if (label[size_t(i)] >= 0 || !in_region[size_t(i)] || !(density[size_t(i)] > threshold)) continue;
        const int32_t id = int32_t(sizes.size());
        int64_t count = 0;
        label[size_t(i)] = id;
        stack.push_back(i);
        while (!stack.empty()) {
            const int64_t j = stack.back();
            stack.pop_back();
            ++count;
            const int64_t x = j % R, y = (j / R) % R, z = j / (R * R);
            for (int64_t dz = -1; dz <= 1; ++dz)
                for (int64_t dy = -1; dy <= 1; ++dy)
                    for (int64_t dx = -1; dx <= 1; ++dx) {
                        const int64_t nx = x + dx, ny = y + dy, nz = z + dz;
                        if (nx < 0 || ny < 0 || nz < 0 || nx >= R || ny >= R || nz >= R) continue;
                        const int64_t k = nx + ny * R + nz * R * R;
                        if (label[size_t(k)] >= 0 || !in_region[size_t(k)] ||
                            !(density[size_t(k)] > threshold))
                            continue;
                        label[size_t(k)] = id;
                        stack.push_back(k);
                    }
        }
        sizes.push_back(count);
    }
    st.components = int64_t(sizes.size());
    const int64_t largest =
        sizes.empty() ? -1 : int64_t(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
    std::vector<uint8_t> keep(sizes.size(), 0);
    for (size_t k = 0; k < sizes.size(); ++k) {
        keep[k] = int64_t(k) == largest || sizes[k] >= s.min_component_cells;
        st.kept_components += keep[k];
        if (!keep[k]) st.cut_as_floaters += sizes[k];
    }

    for (size_t i = 0; i < density.size(); ++i) {
        bool kept;
        if (int64_t(i) < per_cascade)
            kept = label[i] >= 0 && keep[size_t(label[i])];
        else
            kept = in_region[i] && density[i] > threshold;
        if (!kept) density[i] = 0.0f;
        st.occupied_after += kept;
    }
    return st;
}

IsolationStats isolate_model(NerfModel& model, const IsolationSettings& s, const std::string& where) {
    if (!model.object)
        throw Error(where +
                    ": the model has no object frame (OBJF section): `nerfpt capture` stores one when it "
                    "finds the supporting plane");
    IsolationInput in;
    in.cascades = model.occupancy.cascades();
    in.resolution = model.occupancy.resolution();
    in.occupied_threshold = model.config.occupancy.threshold;
    in.model_to_object = model_to_object(*model.object, model.world_to_model);
    in.box_min = model.object->box_min;
    in.box_max = model.object->box_max;
    in.min_step = model.march_params().min_step;
    std::vector<float> density = model.occupancy.density();
    const IsolationStats st = isolate_object(density, in, s);
    model.occupancy.set_density(std::move(density), in.occupied_threshold);
    model.object->object_only = true;  // the exact cut (the box, the plane) is the renderer's
    return st;
}

}  // namespace npt::nerf
