// The CPU backend's ray queries: one Embree 3 triangle geometry per scene mesh (geomID = mesh index),
// committed once; EmbreeTracer answers the integrator's two questions (first hit, segment blocked) for one
// ray at a time.
#pragma once

#include <embree3/rtcore.h>

#include <cassert>

#include <vector>

#include "render/surface.h"
#include "scene/animation.h"
#include "scene/scene.h"

namespace npt::render::cpu {

class EmbreeScene {
  public:
    // Meshes an animation moves are built for refitting, in a dynamic scene (Embree's two levels: only the
    // moved geometries' BVHs are touched on a commit).
    explicit EmbreeScene(const scene::Scene& scene);
    ~EmbreeScene();
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    RTCScene handle() const { return m_scene; }
    // After scene::pose_scene: copies the moved meshes' vertices and indices into their geometries, refits
    // those, and commits the scene.
    void update(const scene::Scene& scene, const scene::PoseChanges& changes);

  private:
    RTCDevice m_device = nullptr;
    RTCScene m_scene = nullptr;
};

// What Embree accepts (its RayK::valid(), asserted inside rtcIntersect1/rtcOccluded1 even in Debian's release
// build): finite origin and direction with no component beyond FLT_LARGE = 1.844e18, and tmax not NaN.
// Loaders keep the world within scene::k_max_world_coordinate, so a ray failing this is a bug upstream.
inline bool embree_accepts(const Ray& ray, float tmax) {
    constexpr float k_flt_large = 1.844e18f;
    const auto ok = [](Vec3 v) {
        return fabsf(v.x) <= k_flt_large && fabsf(v.y) <= k_flt_large && fabsf(v.z) <= k_flt_large;
    };
    return ok(ray.o) && ok(ray.d) && !(tmax != tmax);  // the comparisons are false for NaN
}

class EmbreeTracer {
  public:
    explicit EmbreeTracer(const EmbreeScene& scene) : m_scene(scene.handle()) {}

    // A ray Embree would reject is a miss (debug builds assert): a NaN or runaway ray never reaches Embree.
    bool intersect(const Ray& ray, float tmax, Hit* hit) const {
        assert(embree_accepts(ray, tmax) && "non-finite or huge ray");
        if (!embree_accepts(ray, tmax)) return false;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRayHit rh;
        rh.ray.org_x = ray.o.x;
        rh.ray.org_y = ray.o.y;
        rh.ray.org_z = ray.o.z;
        rh.ray.dir_x = ray.d.x;
        rh.ray.dir_y = ray.d.y;
        rh.ray.dir_z = ray.d.z;
        rh.ray.tnear = 0.0f;
        rh.ray.tfar = tmax;
        rh.ray.time = 0.0f;
        rh.ray.mask = 0xFFFFFFFFu;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(m_scene, &ctx, &rh);
        if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
        hit->t = rh.ray.tfar;
        hit->mesh = rh.hit.geomID;
        hit->prim = rh.hit.primID;
        hit->u = rh.hit.u;
        hit->v = rh.hit.v;
        return true;
    }

    // A ray Embree would reject counts as blocked, so it adds no light (debug builds assert).
    bool occluded(const Ray& ray, float tmax) const {
        assert(embree_accepts(ray, tmax) && "non-finite or huge ray");
        if (!embree_accepts(ray, tmax)) return true;
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        RTCRay r;
        r.org_x = ray.o.x;
        r.org_y = ray.o.y;
        r.org_z = ray.o.z;
        r.dir_x = ray.d.x;
        r.dir_y = ray.d.y;
        r.dir_z = ray.d.z;
        r.tnear = 0.0f;
        r.tfar = tmax;
        r.time = 0.0f;
        r.mask = 0xFFFFFFFFu;
        r.id = 0;
        r.flags = 0;
        rtcOccluded1(m_scene, &ctx, &r);
        return r.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
    }

  private:
    RTCScene m_scene;
};

}  // namespace npt::render::cpu
