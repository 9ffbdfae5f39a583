// Turning decoded images into scene textures (linear RGBA float), shared by the glTF, OBJ and JSON loaders.
#pragma once

#include <string>

#include "core/image.h"
#include "scene/scene.h"

namespace npt::scene {

// Expands RGB to RGBA (alpha 1).
Texture make_texture(const Image& image, std::string name);

}  // namespace npt::scene
