// glTF animation: node translation/rotation/scale channels sampled at a time in seconds, the node hierarchy's
// world transforms at that time, and the loaded scene moved to it (rigid meshes, cameras, lights, volume cubes).
// Format-independent: the glTF loader fills these structs (gltf_animation.cpp), render code only calls
// pose_scene.
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "core/transform.h"
#include "scene/scene.h"

namespace npt::scene {

enum class AnimationPath { Translation, Rotation, Scale };
enum class Interpolation { Step, Linear, CubicSpline };

// One sampler bound to one node property. `values` holds width() numbers per key (4 for rotation, x y z w; 3
// otherwise), or with CubicSpline 3 x width() per key: in-tangent, value, out-tangent (the glTF layout).
struct AnimationChannel {
    int node = -1;
    AnimationPath path = AnimationPath::Translation;
    Interpolation interpolation = Interpolation::Linear;
    std::vector<double> times;   // seconds, strictly increasing
    std::vector<double> values;
    int width() const { return path == AnimationPath::Rotation ? 4 : 3; }
};

struct Animation {
    std::string name;
    std::vector<AnimationChannel> channels;
    double start = 0.0, end = 0.0;  // seconds: the first and last key over all channels
};

// A node of the file's hierarchy at rest: its TRS (or a fixed matrix, which no channel may target).
struct AnimationNode {
    std::string name;
    int parent = -1;
    std::array<double, 3> translation{0, 0, 0};
    std::array<double, 4> rotation{0, 0, 0, 1};  // x y z w
    std::array<double, 3> scale{1, 1, 1};
    bool has_matrix = false;
    Mat4 matrix;
};

// The value of `channel` at time t (seconds): before the first key the first value, after the last the last
// (glTF's clamping). Rotations are unit quaternions (LINEAR by slerp along the shorter arc, CUBICSPLINE
// normalised after the Hermite spline, as the spec asks). Returns width() numbers; the rest are 0.
std::array<double, 4> sample_channel(const AnimationChannel& channel, double t);

// Every node's world transform at time t: its rest TRS with the animation's channels applied, times its
// parents', times `placement` (where an including JSON scene put the file). `animation` may be null (rest).
std::vector<Mat4> world_transforms(const std::vector<AnimationNode>& nodes, const Animation* animation, double t,
                                   const Mat4& placement = Mat4::identity());

// A scene object that follows a node. Only objects under an animated node are recorded.
struct MeshBinding {
    size_t mesh = 0;  // into Scene::meshes
    int node = -1;
    Mesh local;       // the mesh in its node's space (positions, normals), as read from the file
};
struct NodeBinding {
    size_t index = 0;  // into Scene::cameras, Scene::lights or Scene::volumes
    int node = -1;
};

// What a scene needs to move to a time: the file's hierarchy, the chosen animation and who follows which node.
struct SceneAnimation {
    std::string file;  // for messages
    std::vector<AnimationNode> nodes;
    Mat4 placement;
    Animation animation;               // the one chosen (--animation NAME, else the file's first)
    std::vector<std::string> names;    // every animation in the file, for `info` and messages
    double fps = 24.0;                 // scene extras "fps", else 24
    std::vector<MeshBinding> meshes;
    std::vector<NodeBinding> cameras, lights, volumes;
    // The lens of each bound camera (yfov, aspect do not animate in glTF without KHR_animation_pointer).
};

// What pose_scene changed, so that a renderer updates only that.
struct PoseChanges {
    std::vector<size_t> meshes;  // indices into Scene::meshes whose positions/normals/indices were rewritten
    bool cameras = false;
    bool lights = false;   // punctual lights moved (emissive meshes are in `meshes`)
    bool volumes = false;  // a volume cube's local_to_world changed
    bool any() const { return !meshes.empty() || cameras || lights || volumes; }
};

// Moves the scene's animated objects to time t (seconds). Objects whose transform is the same as the one they
// have now are left alone and not reported. Throws npt::Error naming the file and object when the pose
// leaves the world bounds (check_world_point) or makes a transform singular.
PoseChanges pose_scene(Scene& scene, double t);

// A camera's frame from its node's world transform: position, and forward/right/up with scale and shear
// removed. Throws npt::Error "<where>: ..." when degenerate or out of bounds.
void place_camera(Camera& camera, const Mat4& world, const std::string& where);

// The time of frame `frame` at `fps` frames per second: frame / fps, Blender's glTF exporter's mapping (its
// frame 1 is at 1/fps seconds).
inline double frame_time(double frame, double fps) { return frame / fps; }

}  // namespace npt::scene
