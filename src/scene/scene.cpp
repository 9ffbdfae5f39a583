#include "scene/scene.h"

#include "core/error.h"

namespace npt::scene {

size_t Scene::triangle_count() const {
    size_t n = 0;
    for (const auto& m : meshes) n += m.triangle_count();
    return n;
}

}  // namespace npt::scene
