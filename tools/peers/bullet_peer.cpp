/* bullet_peer.cpp: the Bullet 3 benchmark peer (btBvhTriangleMeshShape with a quantized BVH, performRaycast). */
#include "config.h"

#include <btBulletCollisionCommon.h>
#include <BulletCollision/CollisionDispatch/SphereTriangleDetector.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btPointCollector.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
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

btScalar segment_length(const shape_query &q)
{
    return btVector3(q.p1[0] - q.p0[0], q.p1[1] - q.p0[1], q.p1[2] - q.p0[2]).length();
}

/* The query's shape as Bullet holds it, built on the stack per query (no allocation), placed by `place`
 * at the shape's start. Bullet's capsule stands along its local y axis. */
struct query_shape {
    btSphereShape sphere;
    btCapsuleShape capsule;
    btBoxShape box;
    const btConvexShape *shape;
    btTransform place;

    query_shape(shape_kind kind, const shape_query &q)
        : sphere(q.size[0]), capsule(q.size[0], segment_length(q)), box(btVector3(q.size[0], q.size[1], q.size[2]))
    {
        btVector3 p0(q.p0[0], q.p0[1], q.p0[2]), p1(q.p1[0], q.p1[1], q.p1[2]);
        place.setIdentity();
        place.setOrigin(0.5f * (p0 + p1));
        if (kind == SHAPE_SPHERE) {
            shape = &sphere;
        } else if (kind == SHAPE_BOX || kind == SHAPE_ORIENTED_BOX) {
            box.setMargin(0.0f);
            place.setRotation(btQuaternion(q.rotation[0], q.rotation[1], q.rotation[2], q.rotation[3]));
            shape = &box;
        } else {
            btVector3 axis = p1 - p0;
            btScalar length = axis.length();
            if (length > 0.0f)
                place.setRotation(shortestArcQuat(btVector3(0, 1, 0), axis / length));
            shape = &capsule;
        }
    }
};

/* Keeps the first contact: processTriangle calls reportHit only for a fraction below m_hitFraction. */
struct sweep_callback : public btTriangleConvexcastCallback {
    int triangle = -1;
    sweep_callback(const btConvexShape *shape, const btTransform &from, const btTransform &to)
        : btTriangleConvexcastCallback(shape, from, to, btTransform::getIdentity(), 0.0f)
    {
    }
    btScalar reportHit(const btVector3 &, const btVector3 &, btScalar fraction, int, int index) override
    {
        triangle = index;
        m_hitFraction = fraction;
        return fraction;
    }
};

/* Passes on the triangles of the box walk that the exact test finds at distance <= 0. */
struct overlap_callback : public btTriangleCallback {
    shape_kind kind;
    query_shape *q;
    void (*add)(void *user, uint32_t tri);
    void *user;
    overlap_callback(shape_kind k, query_shape *s, void (*a)(void *, uint32_t), void *u)
        : kind(k), q(s), add(a), user(u)
    {
    }
    void processTriangle(btVector3 *v, int, int index) override
    {
        btTriangleShape triangle(v[0], v[1], v[2]);
        triangle.setMargin(0.0f);
        btDiscreteCollisionDetectorInterface::ClosestPointInput input;
        input.m_transformA = q->place;
        input.m_transformB.setIdentity();
        btPointCollector result;
        if (kind == SHAPE_SPHERE) {
            SphereTriangleDetector detector(&q->sphere, &triangle, 0.0f);
            detector.getClosestPoints(input, result, nullptr);
        } else {
            btVoronoiSimplexSolver simplex;
            btGjkEpaPenetrationDepthSolver epa;
            btGjkPairDetector detector(q->shape, &triangle, &simplex, &epa);
            detector.getClosestPoints(input, result, nullptr);
        }
        if (result.m_hasResult && result.m_distance <= 0.0f)
            add(user, (uint32_t)index);
    }
};

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

extern "C" void bullet_peer_sweep(const bullet_peer *peer, shape_kind kind, const shape_query *queries, size_t count,
                                  shape_answer *out)
{
    for (size_t i = 0; i < count; i++) {
        const shape_query &q = queries[i];
        query_shape s(kind, q);
        btTransform to = s.place;
        to.setOrigin(s.place.getOrigin() + btVector3(q.delta[0], q.delta[1], q.delta[2]));
        sweep_callback cb(s.shape, s.place, to);
        /* as convexSweepTest: the shape's box under its rotation only, moved from start to end */
        btTransform rotation(s.place.getBasis());
        btVector3 box_min, box_max;
        s.shape->getAabb(rotation, box_min, box_max);
        peer->shape->performConvexcast(&cb, s.place.getOrigin(), to.getOrigin(), box_min, box_max);
        shape_answer &a = out[i];
        a.count = 0;
        a.set_hash = 0;
        a.tri = cb.triangle < 0 ? CBVH_NO_HIT : (uint32_t)cb.triangle;
        a.t = cb.triangle < 0 ? INFINITY : cb.m_hitFraction;
    }
}

extern "C" void bullet_peer_overlap_each(const bullet_peer *peer, shape_kind kind, const shape_query *query,
                                         void (*add)(void *user, uint32_t tri), void *user)
{
    query_shape s(kind, *query);
    overlap_callback cb(kind, &s, add, user);
    btVector3 box_min, box_max;
    s.shape->getAabb(s.place, box_min, box_max);
    peer->shape->processAllTriangles(&cb, box_min, box_max);
}

extern "C" void bullet_peer_overlap(const bullet_peer *peer, shape_kind kind, const shape_query *queries,
                                    size_t count, shape_answer *out)
{
    shape_answers_from_each(
        peer,
        [](const void *p, shape_kind k, const shape_query *q, void (*add)(void *, uint32_t), void *user) {
            bullet_peer_overlap_each(static_cast<const bullet_peer *>(p), k, q, add, user);
        },
        kind, queries, count, out);
}
