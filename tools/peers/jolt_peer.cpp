/* jolt_peer.cpp: the Jolt Physics benchmark peer (a MeshShape; CastRay, CastShape and CollideShape on it). */
#include "config.h"

#include <Jolt/Jolt.h>

#include <Jolt/Core/Factory.h>
#include <Jolt/Core/Memory.h>
#include <Jolt/Physics/Collision/CastResult.h>
#include <Jolt/Physics/Collision/CollideShape.h>
#include <Jolt/Physics/Collision/CollisionCollectorImpl.h>
#include <Jolt/Physics/Collision/CollisionDispatch.h>
#include <Jolt/Physics/Collision/RayCast.h>
#include <Jolt/Physics/Collision/Shape/BoxShape.h>
#include <Jolt/Physics/Collision/Shape/CapsuleShape.h>
#include <Jolt/Physics/Collision/Shape/MeshShape.h>
#include <Jolt/Physics/Collision/Shape/SphereShape.h>
#include <Jolt/Physics/Collision/ShapeCast.h>
#include <Jolt/Physics/Collision/ShapeFilter.h>
#include <Jolt/RegisterTypes.h>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <new>

#include "peers.h"

struct jolt_peer {
    JPH::Ref<JPH::Shape> shape;
    const JPH::MeshShape *mesh;
};

namespace
{

/* Jolt's allocator hooks, factory and type registry are process-wide: set up by the first peer, torn down
 * by the last (peers are created and destroyed on one thread). */
int jolt_users;

void jolt_acquire()
{
    if (jolt_users++ > 0)
        return;
    JPH::RegisterDefaultAllocator();
    JPH::Factory::sInstance = new JPH::Factory();
    JPH::RegisterTypes();
}

void jolt_release()
{
    if (--jolt_users > 0)
        return;
    JPH::UnregisterTypes();
    delete JPH::Factory::sInstance;
    JPH::Factory::sInstance = nullptr;
}

double now_seconds(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* cbvh's triangle index, kept in the triangle's user data: Jolt reorders the triangles. */
uint32_t triangle_of(const jolt_peer *peer, const JPH::SubShapeID &id)
{
    return peer->mesh->GetTriangleUserData(id);
}

/* Jolt casts segments: from org + tmin * dir along (tmax - tmin) * dir. */
JPH::RayCast segment(const cbvh_ray &r)
{
    const float length = r.tmax - r.tmin;
    return JPH::RayCast(
        JPH::Vec3(r.org[0] + r.tmin * r.dir[0], r.org[1] + r.tmin * r.dir[1], r.org[2] + r.tmin * r.dir[2]),
        JPH::Vec3(length * r.dir[0], length * r.dir[1], length * r.dir[2]));
}

/* Every query of the bench sees both faces of a triangle, as cbvh's do, and takes every edge as active (no
 * active-edge processing: the bench compares the triangles touched and the time of contact, not normals). */
JPH::ShapeCastSettings sweep_settings()
{
    JPH::ShapeCastSettings s;
    s.SetBackFaceMode(JPH::EBackFaceMode::CollideWithBackFaces);
    s.mActiveEdgeMode = JPH::EActiveEdgeMode::CollideWithAll;
    return s;
}

JPH::CollideShapeSettings overlap_settings()
{
    JPH::CollideShapeSettings s;
    s.mBackFaceMode = JPH::EBackFaceMode::CollideWithBackFaces;
    s.mActiveEdgeMode = JPH::EActiveEdgeMode::CollideWithAll;
    return s;
}

/* The query's shape as Jolt holds it, built on the stack per query (embedded: no reference counting, no
 * allocation), with `place` its center of mass transform at the start. Jolt's capsule stands along its local
 * y axis around its center; a capsule of no length is its sphere. Boxes have convex radius 0: the exact box,
 * as the other engines answer for. */
struct query_shape {
    JPH::SphereShape sphere;
    JPH::CapsuleShape capsule;
    JPH::BoxShape box;
    const JPH::Shape *shape;
    JPH::Mat44 place;

    static float half_length(const shape_query &q)
    {
        const float d[3] = {q.p1[0] - q.p0[0], q.p1[1] - q.p0[1], q.p1[2] - q.p0[2]};
        return 0.5f * std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    }

    query_shape(shape_kind kind, const shape_query &q)
        : sphere(q.size[0]), capsule(half_length(q), q.size[0]),
          box(JPH::Vec3(q.size[0], q.size[1], q.size[2]), 0.0f)
    {
        sphere.SetEmbedded();
        capsule.SetEmbedded();
        box.SetEmbedded();
        const JPH::Vec3 p0(q.p0[0], q.p0[1], q.p0[2]), p1(q.p1[0], q.p1[1], q.p1[2]);
        JPH::Quat rotation = JPH::Quat::sIdentity();
        shape =
            kind == SHAPE_BOX || kind == SHAPE_ORIENTED_BOX ? static_cast<const JPH::Shape *>(&box) : &sphere;
        if (kind == SHAPE_ORIENTED_BOX)
            rotation = JPH::Quat(q.rotation[0], q.rotation[1], q.rotation[2], q.rotation[3]).Normalized();
        if (kind == SHAPE_CAPSULE && half_length(q) > 0.0f) {
            rotation = JPH::Quat::sFromTo(JPH::Vec3::sAxisY(), (p1 - p0).Normalized());
            shape = &capsule;
        }
        place = JPH::Mat44::sRotationTranslation(rotation, 0.5f * (p0 + p1));
    }
};

/* Passes on every triangle CollideShape reports a contact with. */
struct each_collector : public JPH::CollideShapeCollector {
    const jolt_peer *peer;
    void (*add)(void *user, uint32_t tri);
    void *user;
    each_collector(const jolt_peer *p, void (*a)(void *, uint32_t), void *u) : peer(p), add(a), user(u) {}
    void AddHit(const JPH::CollideShapeResult &result) override
    {
        add(user, triangle_of(peer, result.mSubShapeID2));
    }
};

} // namespace

extern "C" jolt_peer *jolt_peer_create(const peer_mesh *mesh, peer_build_info *info, char *err,
                                       size_t err_size)
{
    if (mesh->triangle_count > 0x7FFFFFFF || mesh->vertex_count > 0x7FFFFFFF) {
        snprintf(err, err_size, "jolt: the mesh is too large for Jolt's counts");
        return nullptr;
    }
    jolt_acquire();
    if (!JPH::VerifyJoltVersionID()) {
        jolt_release();
        snprintf(
            err, err_size,
            "jolt: libJolt.a was built with other options than the compile definitions configure read from "
            "its CMake package (JPH_VERSION_ID differs): configure again --with-jolt");
        return nullptr;
    }
    jolt_peer *p = new (std::nothrow) jolt_peer();
    if (!p) {
        jolt_release();
        snprintf(err, err_size, "jolt: out of memory");
        return nullptr;
    }
    double start = now_seconds(CLOCK_MONOTONIC), cpu_start = now_seconds(CLOCK_PROCESS_CPUTIME_ID);
    /* Jolt copies the mesh into its own compressed tree; the settings (its input lists) go once it is built.
     */
    {
        JPH::VertexList vertices;
        vertices.reserve(mesh->vertex_count);
        for (size_t i = 0; i < mesh->vertex_count; i++)
            vertices.push_back(
                JPH::Float3(mesh->positions[3 * i], mesh->positions[3 * i + 1], mesh->positions[3 * i + 2]));
        JPH::IndexedTriangleList triangles;
        triangles.reserve(mesh->triangle_count);
        for (size_t i = 0; i < mesh->triangle_count; i++)
            triangles.push_back(JPH::IndexedTriangle(mesh->indices[3 * i], mesh->indices[3 * i + 1],
                                                     mesh->indices[3 * i + 2], 0, (JPH::uint)i));
        JPH::MeshShapeSettings settings(std::move(vertices), std::move(triangles));
        settings.mPerTriangleUserData = true;
        JPH::ShapeSettings::ShapeResult result = settings.Create();
        if (result.HasError()) {
            snprintf(err, err_size, "jolt: MeshShape: %s", result.GetError().c_str());
            delete p;
            jolt_release();
            return nullptr;
        }
        p->shape = result.Get();
        info->seconds = now_seconds(CLOCK_MONOTONIC) - start;
        info->cpu_seconds = now_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu_start;
        /* the same shape without the indices, for its size alone (Create caches its result: new settings) */
        JPH::MeshShapeSettings plain(settings.mTriangleVertices, settings.mIndexedTriangles);
        JPH::ShapeSettings::ShapeResult plain_result = plain.Create();
        const size_t plain_bytes = plain_result.HasError() ? 0 : plain_result.Get()->GetStats().mSizeBytes;
        const size_t bytes = p->shape->GetStats().mSizeBytes;
        info->id_bytes = plain_bytes > 0 && plain_bytes < bytes ? bytes - plain_bytes : 0;
    }
    p->mesh = static_cast<const JPH::MeshShape *>(p->shape.GetPtr());
    const JPH::Shape::Stats stats = p->shape->GetStats();
    info->memory_bytes = stats.mSizeBytes;
    info->mesh_bytes = 0;
    info->dropped_triangles = mesh->triangle_count - stats.mNumTriangles;
    return p;
}

extern "C" void jolt_peer_destroy(jolt_peer *peer)
{
    if (!peer)
        return;
    delete peer;
    jolt_release();
}

extern "C" void jolt_peer_raycast(const jolt_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    for (size_t i = 0; i < count; i++) {
        const cbvh_ray &r = rays[i];
        JPH::RayCastResult result; /* its fraction starts just past 1: a hit at tmax counts */
        cbvh_hit &h = hits[i];
        h.u = h.v = 0.0f;
        if (peer->mesh->CastRay(segment(r), JPH::SubShapeIDCreator(), result)) {
            h.tri = triangle_of(peer, result.mSubShapeID2);
            h.t = r.tmin + result.mFraction * (r.tmax - r.tmin);
        } else {
            h.tri = CBVH_NO_HIT;
            h.t = INFINITY;
        }
    }
}

extern "C" void jolt_peer_occluded(const jolt_peer *peer, const cbvh_ray *rays, size_t count,
                                   uint8_t *occluded)
{
    JPH::RayCastSettings settings;
    settings.SetBackFaceMode(JPH::EBackFaceMode::CollideWithBackFaces);
    for (size_t i = 0; i < count; i++) {
        JPH::AnyHitCollisionCollector<JPH::CastRayCollector> any;
        peer->mesh->CastRay(segment(rays[i]), settings, JPH::SubShapeIDCreator(), any);
        occluded[i] = any.HadHit();
    }
}

extern "C" void jolt_peer_sweep(const jolt_peer *peer, shape_kind kind, const shape_query *queries,
                                size_t count, shape_answer *out)
{
    const JPH::ShapeCastSettings settings = sweep_settings();
    for (size_t i = 0; i < count; i++) {
        const shape_query &q = queries[i];
        query_shape s(kind, q);
        JPH::ShapeCast cast(s.shape, JPH::Vec3::sOne(), s.place,
                            JPH::Vec3(q.delta[0], q.delta[1], q.delta[2]));
        JPH::ClosestHitCollisionCollector<JPH::CastShapeCollector> closest;
        JPH::CollisionDispatch::sCastShapeVsShapeLocalSpace(
            cast, settings, peer->shape, JPH::Vec3::sOne(), JPH::ShapeFilter(), JPH::Mat44::sIdentity(),
            JPH::SubShapeIDCreator(), JPH::SubShapeIDCreator(), closest);
        shape_answer &a = out[i];
        a.count = 0;
        a.set_hash = 0;
        a.tri = closest.HadHit() ? triangle_of(peer, closest.mHit.mSubShapeID2) : CBVH_NO_HIT;
        a.t = closest.HadHit() ? closest.mHit.mFraction : INFINITY;
    }
}

extern "C" void jolt_peer_overlap_first(const jolt_peer *peer, shape_kind kind, const shape_query *queries,
                                        size_t count, shape_answer *out)
{
    const JPH::CollideShapeSettings settings = overlap_settings();
    for (size_t i = 0; i < count; i++) {
        query_shape s(kind, queries[i]);
        JPH::AnyHitCollisionCollector<JPH::CollideShapeCollector> any;
        JPH::CollisionDispatch::sCollideShapeVsShape(
            s.shape, peer->shape, JPH::Vec3::sOne(), JPH::Vec3::sOne(), s.place, JPH::Mat44::sIdentity(),
            JPH::SubShapeIDCreator(), JPH::SubShapeIDCreator(), settings, any);
        shape_answer &a = out[i];
        a.t = INFINITY;
        a.set_hash = 0;
        a.count = any.HadHit() ? 1 : 0;
        a.tri = any.HadHit() ? triangle_of(peer, any.mHit.mSubShapeID2) : CBVH_NO_HIT;
    }
}

extern "C" void jolt_peer_overlap_each(const jolt_peer *peer, shape_kind kind, const shape_query *query,
                                       void (*add)(void *user, uint32_t tri), void *user)
{
    const JPH::CollideShapeSettings settings = overlap_settings();
    query_shape s(kind, *query);
    each_collector each(peer, add, user);
    JPH::CollisionDispatch::sCollideShapeVsShape(s.shape, peer->shape, JPH::Vec3::sOne(), JPH::Vec3::sOne(),
                                                 s.place, JPH::Mat44::sIdentity(), JPH::SubShapeIDCreator(),
                                                 JPH::SubShapeIDCreator(), settings, each);
}

extern "C" void jolt_peer_overlap(const jolt_peer *peer, shape_kind kind, const shape_query *queries,
                                  size_t count, shape_answer *out)
{
    shape_answers_from_each(
        peer,
        [](const void *p, shape_kind k, const shape_query *q, void (*add)(void *, uint32_t), void *user) {
            jolt_peer_overlap_each(static_cast<const jolt_peer *>(p), k, q, add, user);
        },
        kind, queries, count, out);
}
