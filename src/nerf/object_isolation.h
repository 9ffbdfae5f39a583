// The object alone in its model (issue 25): the occupancy grid cut to the cells that overlap the object's box
// above its supporting plane, and cleared of floaters (small connected components), so that every march skips
// the table, the props and the floaters; the model is marked object_only, so that renders cut exactly at the
// box and the plane (object_frame.h). Works on the grid's densities and the object frame; the network is
// untouched.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/transform.h"
#include "core/vec.h"
#include "nerf/nerf_model.h"

namespace npt::nerf {

struct IsolationSettings {
    // Cells lying wholly below this many cells (of cascade 0) above the supporting plane go; 0: the cells that
    // straddle the plane stay, and the renderer cuts at the plane exactly (the model is marked object_only).
    // Cutting the straddling cells lost up to a cell of the object's base (docs/benchmarks.md, "The object
    // alone: an exact cut").
    double plane_margin_cells = 0.0;
    // A component of occupied cells not the largest one is kept only with at least this many cells. 8 = 2^3:
    // the grid resolves a feature only with two cells per axis (sampling), so a smaller component is below
    // what the grid can represent of a real part and is taken for a floater.
    int64_t min_component_cells = 8;
    // The table's own density (a NeRF's surface is a few millimetres thick) reaches above the fitted plane
    // and, inside the box's margin around the object's foot, rendered as a ring of table (docs/benchmarks.md,
    // "the table around the foot"). Cells of cascade 0 whose centre lies below this many cells above the
    // plane are kept only under the object's footprint: the vertical projection of the cells above that
    // layer that are dense (opacity across the cell >= footprint_opacity), widened by footprint_margin_cells.
    // 0: no layer (the plane alone cuts). 3 cells, and 0.4 for a dense cell: against 2 and 0.5 the table
    // wedge in an object's shadow goes and more of the object's own bottom cells stay (docs/benchmarks.md, "a
    // thicker table layer": IoU s5 +0.0026, s11 -0.0002; the object over white s5 +0.5 dB, s11 +0.0).
    double table_layer_cells = 3.0;
    double footprint_opacity = 0.4;
    double footprint_margin_cells = 1.0;
    // The footprint is the projection of the dense cells within this many cells above the lowest dense cell
    // above the layer (the object's foot), not of every dense cell above it: an object wider above than at
    // its foot (a vase's belly, a mushroom's cap) kept the table under its overhang (docs/benchmarks.md, "the
    // foot's footprint"). 0: every dense cell above the layer.
    double footprint_slab_cells = 4.0;
};

// The grid and the object's place, in plain numbers so that a synthetic grid can be tested.
struct IsolationInput {
    int cascades = 1, resolution = 128;
    float occupied_threshold = 0.01f;  // the config's occupancy threshold: occupied = density > min(it, mean)
    Mat4 model_to_object;              // model space ([0,1]^3 cube, occupancy_view.h) -> object space (+Z up,
                                       // supporting plane z = 0)
    Vec3 box_min, box_max;             // the object's box in object space
    // The march's smallest step in model units, for the opacity of a cell (occupancy_cell_opacity).
    float min_step = 0.0f;
};

struct IsolationStats {
    int64_t occupied_before = 0;
    int64_t cut_by_region = 0;    // occupied cells outside the box or under the plane
    int64_t cut_off_footprint = 0;  // occupied cells of the table layer outside the object's footprint
    int64_t cut_as_floaters = 0;  // occupied cells in dropped components
    int64_t components = 0;       // components of cascade 0 inside the region
    int64_t kept_components = 0;
    int64_t occupied_after = 0;
};

// Sets density[cell] = 0 for every cell but those of the kept components (so no cell becomes occupied when
// the grid's mean drops). Components are 26-connected occupied cells of cascade 0; cells of coarser cascades
// keep their density only inside the region. Throws npt::Error when density.size() != cascades *
// resolution^3.
IsolationStats isolate_object(std::vector<float>& density, const IsolationInput& in,
                              const IsolationSettings& s);

// The same on a model that carries its object frame (model.object): its occupancy grid cut and its occupied
// flags recomputed. Throws npt::Error "WHERE: ..." when the model has no object frame. Training the model
// further re-estimates the grid and undoes the cut.
IsolationStats isolate_model(NerfModel& model, const IsolationSettings& s, const std::string& where);

}  // namespace npt::nerf
