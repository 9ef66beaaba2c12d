/* bullet_peer.cpp: the Bullet 3 benchmark peer (btBvhTriangleMeshShape with a quantized BVH, performRaycast). */
#include "config.h"

#include <btBulletCollisionCommon.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <new>

#include "peers.h"

struct bullet_peer {
    btTriangleIndexVertexArray *arrays;
    btBvhTriangleMeshShape *shape;
};

namespace {

double now_seconds(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Keeps the closest hit: returning the fraction makes Bullet reject every
 * later triangle that lies farther (its m_hitFraction clamp). */
struct closest_callback : public btTriangleRaycastCallback {
    int triangle = -1;
    closest_callback(const btVector3 &from, const btVector3 &to) : btTriangleRaycastCallback(from, to) {}
    btScalar reportHit(const btVector3 &, btScalar fraction, int, int index) override
    {
        triangle = index;
        return fraction;
    }
};

/* Stops at the first hit as far as Bullet allows: a hit fraction of 0 makes
 * every later triangle fail its first distance test. */
struct any_callback : public btTriangleRaycastCallback {
    bool hit = false;
    any_callback(const btVector3 &from, const btVector3 &to) : btTriangleRaycastCallback(from, to) {}
    btScalar reportHit(const btVector3 &, btScalar, int, int) override
    {
        hit = true;
        return 0;
    }
};

/* Bullet casts segments: from org + tmin * dir to org + tmax * dir. */
void segment(const cbvh_ray &r, btVector3 &from, btVector3 &to)
{
    from.setValue(r.org[0] + r.tmin * r.dir[0], r.org[1] + r.tmin * r.dir[1], r.org[2] + r.tmin * r.dir[2]);
    to.setValue(r.org[0] + r.tmax * r.dir[0], r.org[1] + r.tmax * r.dir[1], r.org[2] + r.tmax * r.dir[2]);
}

} // namespace

extern "C" bullet_peer *bullet_peer_create(const peer_mesh *mesh, peer_build_info *info, char *err, size_t err_size)
{
    if (mesh->triangle_count > 0x7FFFFFFF || mesh->vertex_count > 0x7FFFFFFF) {
        snprintf(err, err_size, "bullet: the mesh is too large for Bullet's int counts");
        return nullptr;
    }
    bullet_peer *p = new (std::nothrow) bullet_peer();
    if (!p) {
        snprintf(err, err_size, "bullet: out of memory");
        return nullptr;
    }
    double start = now_seconds(CLOCK_MONOTONIC), cpu_start = now_seconds(CLOCK_PROCESS_CPUTIME_ID);
    /* Bullet takes non-const pointers but only reads the arrays. */
    p->arrays = new btTriangleIndexVertexArray((int)mesh->triangle_count, (int *)mesh->indices,
                                               3 * (int)sizeof(uint32_t), (int)mesh->vertex_count,
                                               (btScalar *)mesh->positions, 3 * (int)sizeof(float));
    p->shape = new btBvhTriangleMeshShape(p->arrays, true, true);
    info->seconds = now_seconds(CLOCK_MONOTONIC) - start;
    info->cpu_seconds = now_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu_start;
    const btOptimizedBvh *bvh = p->shape->getOptimizedBvh();
    info->memory_bytes = bvh ? bvh->calculateSerializeBufferSize() : 0;
    info->mesh_bytes = 12u * (uint64_t)mesh->vertex_count + 12u * (uint64_t)mesh->triangle_count;
    return p;
}

extern "C" void bullet_peer_destroy(bullet_peer *peer)
{
    if (!peer)
        return;
    delete peer->shape;
    delete peer->arrays;
    delete peer;
}

extern "C" void bullet_peer_raycast(const bullet_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    for (size_t i = 0; i < count; i++) {
        const cbvh_ray &r = rays[i];
        btVector3 from, to;
        segment(r, from, to);
        closest_callback cb(from, to);
        peer->shape->performRaycast(&cb, from, to);
        cbvh_hit &h = hits[i];
        h.u = h.v = 0.0f;
        if (cb.triangle < 0) {
            h.tri = CBVH_NO_HIT;
            h.t = INFINITY;
        } else {
            h.tri = (uint32_t)cb.triangle;
            h.t = r.tmin + cb.m_hitFraction * (r.tmax - r.tmin);
        }
    }
}

extern "C" void bullet_peer_occluded(const bullet_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded)
{
    for (size_t i = 0; i < count; i++) {
        btVector3 from, to;
        segment(rays[i], from, to);
        any_callback cb(from, to);
        peer->shape->performRaycast(&cb, from, to);
        occluded[i] = cb.hit;
    }
}
