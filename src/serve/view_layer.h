// What the viewer's page shows: the render itself (beauty) or one of the film's other outputs
// (render/film.h), made viewable as an 8-bit picture through the same accumulate-and-tone-map path as the
// beauty: alpha as grey, the albedo as colour, the normal as 0.5 + n / 2 (world space), the depth as grey
// from white (at the camera) to black (at depth_range and beyond, and where the ray met nothing).
#pragma once

#include <optional>
#include <string>

#include "core/image.h"
#include "render/film.h"
#include "render/renderer.h"

namespace npt::serve {

enum class ViewLayer { beauty, alpha, albedo, normal, depth };

// "beauty", "alpha", "albedo", "normal", "depth"; nullopt for anything else.
std::optional<ViewLayer> parse_view_layer(const std::string& name);
const char* view_layer_name(ViewLayer layer);

// The options of a pass that shows `layer`: the alpha needs the transparent film, the AOVs their layer.
render::RenderOptions view_options(render::RenderOptions options, ViewLayer layer);

// The pass (`rendered`: what the renderer returned, `aovs`: its layers) as a linear RGB image whose tone map
// at exposure 0 shows `layer` as described above. Not for the beauty, which is shown as rendered.
Image view_image(ViewLayer layer, const Image& rendered, const render::AovImages& aovs, float depth_range);

}  // namespace npt::serve
