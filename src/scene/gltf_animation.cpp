// glTF `animations` into scene::Animation, and the node hierarchy at rest into scene::AnimationNode: every
// sampler and channel checked (accessor types and counts, increasing finite times, finite values, known paths
// and interpolations, target nodes that exist and carry no matrix) with one-line errors naming the field.
#include <spdlog/spdlog.h>

#include <cmath>

#include "core/error.h"
#include "scene/gltf_internal.h"

namespace npt::scene::gltf {

namespace {

Interpolation parse_interpolation(const std::string& text, const std::string& where) {
    if (text.empty() || text == "LINEAR") return Interpolation::Linear;  // the spec's default
    if (text == "STEP") return Interpolation::Step;
    if (text == "CUBICSPLINE") return Interpolation::CubicSpline;
    throw Error(where + ".interpolation: unknown interpolation '" + text + "' (LINEAR, STEP or CUBICSPLINE)");
}

std::string animation_label(const tinygltf::Animation& a, size_t index) {
    return a.name.empty() ? fmt::format("#{}", index) : fmt::format("'{}'", a.name);
}

Animation read_one(const Context& ctx, size_t index) {
    const tinygltf::Animation& ga = ctx.model.animations[index];
    const std::string prefix = ctx.file + ": animations[" + std::to_string(index) + "]";
    Animation out;
    out.name = ga.name;
    bool warned_weights = false;
    bool first = true;
    for (size_t ci = 0; ci < ga.channels.size(); ++ci) {
        const tinygltf::AnimationChannel& gc = ga.channels[ci];
        const std::string where = prefix + ".channels[" + std::to_string(ci) + "]";
        AnimationChannel c;
        if (gc.target_path == "translation") {
            c.path = AnimationPath::Translation;
        } else if (gc.target_path == "rotation") {
            c.path = AnimationPath::Rotation;
        } else if (gc.target_path == "scale") {
            c.path = AnimationPath::Scale;
        } else if (gc.target_path == "weights") {
            // Morph targets: our meshes have none (the loader reads no `targets`), so their weights move nothing.
            if (!warned_weights)
                spdlog::warn("{}.target.path: morph target weights are not supported; such channels are ignored",
                             where);
            warned_weights = true;
            continue;
        } else {
            throw Error(where + ".target.path: unknown path '" + gc.target_path +
                        "' (translation, rotation, scale or weights)");
        }
        if (gc.target_node < 0 || size_t(gc.target_node) >= ctx.model.nodes.size())
            throw Error(where + ".target.node: node " + std::to_string(gc.target_node) + " does not exist (the file has " +
                        std::to_string(ctx.model.nodes.size()) + ")");
        if (ctx.model.nodes[size_t(gc.target_node)].matrix.size() == 16)
            throw Error(where + ".target.node: node " + std::to_string(gc.target_node) +
                        " has a `matrix`, which animations may not target (glTF 2.0, 5.25)");
        c.node = gc.target_node;
        if (gc.sampler < 0 || size_t(gc.sampler) >= ga.samplers.size())
            throw Error(where + ".sampler: sampler " + std::to_string(gc.sampler) + " does not exist (the animation has " +
                        std::to_string(ga.samplers.size()) + ")");
        const tinygltf::AnimationSampler& gs = ga.samplers[size_t(gc.sampler)];
        const std::string swhere = prefix + ".samplers[" + std::to_string(gc.sampler) + "]";
        c.interpolation = parse_interpolation(gs.interpolation, swhere);
        c.times = read_floats(ctx, gs.input, TINYGLTF_TYPE_SCALAR, fmt::format("input of {}", swhere.substr(ctx.file.size() + 2)));
        const size_t n = c.times.size();
        if (n == 0) throw Error(swhere + ".input: accessor " + std::to_string(gs.input) + " has no keys");
        for (size_t k = 0; k < n; ++k) {
            if (!std::isfinite(c.times[k]))
                throw Error(swhere + ".input: key " + std::to_string(k) + " time is not finite");
            if (k > 0 && !(c.times[k] > c.times[k - 1]))
                throw Error(swhere + ".input: key times must increase strictly; key " + std::to_string(k) + " (" +
                            std::to_string(c.times[k]) + " s) follows " + std::to_string(c.times[k - 1]) + " s");
        }
        if (c.interpolation == Interpolation::CubicSpline && n < 2)
            throw Error(swhere + ": CUBICSPLINE needs at least 2 keys, the input has 1");
        const int type = c.width() == 4 ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3;
        c.values = read_floats(ctx, gs.output, type, fmt::format("output of {}", swhere.substr(ctx.file.size() + 2)));
        const size_t per_key = c.interpolation == Interpolation::CubicSpline ? 3 : 1;
        const size_t elements = c.values.size() / size_t(c.width());
        if (elements != n * per_key)
            throw Error(swhere + ".output: accessor " + std::to_string(gs.output) + " has " + std::to_string(elements) +
                        " elements, expected " + std::to_string(n * per_key) + " for " + std::to_string(n) + " keys" +
                        (per_key == 3 ? " (CUBICSPLINE: in-tangent, value, out-tangent per key)" : ""));
        for (size_t k = 0; k < c.values.size(); ++k)
            if (!std::isfinite(c.values[k]))
                throw Error(swhere + ".output: element " + std::to_string(k / size_t(c.width())) + " is not finite");
        if (c.path == AnimationPath::Rotation)
            for (size_t e = 0; e < elements; ++e) {
                if (c.interpolation == Interpolation::CubicSpline && e % 3 != 1) continue;  // tangents may be zero
                const double* q = &c.values[e * 4];
                if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 0))
                    throw Error(swhere + ".output: rotation " + std::to_string(e) + " is a zero quaternion");
            }
        out.start = first ? c.times.front() : std::min(out.start, c.times.front());
        out.end = first ? c.times.back() : std::max(out.end, c.times.back());
        first = false;
        out.channels.push_back(std::move(c));
    }
    return out;
}

}  // namespace

std::vector<AnimationNode> rest_nodes(const Context& ctx) {
    const auto& model = ctx.model;
    std::vector<AnimationNode> nodes(model.nodes.size());
    for (size_t i = 0; i < model.nodes.size(); ++i) {
        const tinygltf::Node& n = model.nodes[i];
        AnimationNode& a = nodes[i];
        a.name = n.name;
        if (n.matrix.size() == 16) {
            a.has_matrix = true;
            a.matrix = Mat4::from_column_major(n.matrix.data());
        }
        if (n.translation.size() == 3) a.translation = {n.translation[0], n.translation[1], n.translation[2]};
        if (n.rotation.size() == 4) a.rotation = {n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]};
        if (n.scale.size() == 3) a.scale = {n.scale[0], n.scale[1], n.scale[2]};
    }
    // Parents from `children`; a node listed twice is refused when the tree is walked (the loader's cycle and
    // shared-child checks), so the first parent is kept here.
    for (size_t i = 0; i < model.nodes.size(); ++i)
        for (int c : model.nodes[i].children)
            if (c >= 0 && size_t(c) < nodes.size() && nodes[size_t(c)].parent < 0 && size_t(c) != i)
                nodes[size_t(c)].parent = int(i);
    return nodes;
}

bool read_animation(const Context& ctx, const std::string& name, Animation& out, std::vector<std::string>& names) {
    const auto& anims = ctx.model.animations;
    names.clear();
    for (size_t i = 0; i < anims.size(); ++i) names.push_back(anims[i].name);
    if (anims.empty()) {
        if (!name.empty()) throw Error(ctx.file + ": --animation '" + name + "': the file has no animations");
        return false;
    }
    size_t chosen = 0;
    if (!name.empty()) {
        chosen = anims.size();
        for (size_t i = 0; i < anims.size() && chosen == anims.size(); ++i)
            if (anims[i].name == name) chosen = i;
        if (chosen == anims.size()) {
            std::string list;
            for (size_t i = 0; i < anims.size(); ++i)
                list += fmt::format("{}{}", list.empty() ? "" : ", ", animation_label(anims[i], i));
            throw Error(ctx.file + ": --animation '" + name + "' not found (available: " + list + ")");
        }
    }
    // Every animation is checked, not only the chosen one: a broken file fails the same whichever is picked.
    for (size_t i = 0; i < anims.size(); ++i) {
        Animation a = read_one(ctx, i);
        if (i == chosen) out = std::move(a);
    }
    if (anims.size() > 1 && name.empty())
        spdlog::info("{}: {} animations; playing {} (choose with --animation NAME)", ctx.file, anims.size(),
                     animation_label(anims[chosen], chosen));
    return true;
}

}  // namespace npt::scene::gltf
