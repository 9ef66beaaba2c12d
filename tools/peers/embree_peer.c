/* embree_peer.c: the Embree 3 benchmark peer (shared-buffer triangle scene, single rays, 16-ray packets). */
#include "config.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "peers.h"

struct embree_peer {
    RTCDevice device;
    RTCScene scene;
    int64_t memory; /* bytes Embree holds, updated by the monitor from its build threads */
};

/* Embree reports allocations (bytes > 0) and releases (bytes < 0); keep the balance. */
static bool memory_monitor(void *user, ssize_t bytes, bool post)
{
    (void)post;
    __atomic_add_fetch((int64_t *)user, (int64_t)bytes, __ATOMIC_RELAXED);
    return true;
}

static double now_seconds(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

embree_peer *embree_peer_create(const peer_mesh *mesh, int robust, int threads, peer_build_info *info,
                                char *err, size_t err_size)
{
    embree_peer *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, err_size, "embree: out of memory");
        return NULL;
    }
    char config[64] = "";
    if (threads > 0)
        snprintf(config, sizeof config, "threads=%d", threads);
    p->device = rtcNewDevice(config);
    if (!p->device) {
        snprintf(err, err_size, "embree: rtcNewDevice(\"%s\") failed (error %d)", config,
                 (int)rtcGetDeviceError(NULL));
        free(p);
        return NULL;
    }
    rtcSetDeviceMemoryMonitorFunction(p->device, memory_monitor, &p->memory);
    /* Device creation (thread pool start) is not part of the build. */
    double start = now_seconds(CLOCK_MONOTONIC), cpu_start = now_seconds(CLOCK_PROCESS_CPUTIME_ID);
    p->scene = rtcNewScene(p->device);
    rtcSetSceneFlags(p->scene, robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    RTCGeometry geom = rtcNewGeometry(p->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, mesh->positions, 0,
                               3 * sizeof(float), mesh->vertex_count);
    rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh->indices, 0,
                               3 * sizeof(uint32_t), mesh->triangle_count);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(p->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(p->scene);
    double seconds = now_seconds(CLOCK_MONOTONIC) - start;
    double cpu_seconds = now_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu_start;
    enum RTCError code = rtcGetDeviceError(p->device);
    if (code != RTC_ERROR_NONE) {
        snprintf(err, err_size, "embree: building the scene failed (error %d)", (int)code);
        embree_peer_destroy(p);
        return NULL;
    }
    info->seconds = seconds;
    info->cpu_seconds = cpu_seconds;
    int64_t memory = __atomic_load_n(&p->memory, __ATOMIC_RELAXED);
    info->memory_bytes = memory > 0 ? (uint64_t)memory : 0;
    info->mesh_bytes = 12u * (uint64_t)mesh->vertex_count + 12u * (uint64_t)mesh->triangle_count;
    return p;
}

void embree_peer_destroy(embree_peer *peer)
{
    if (!peer)
        return;
    if (peer->scene)
        rtcReleaseScene(peer->scene);
    rtcReleaseDevice(peer->device);
    free(peer);
}

static void set_ray(struct RTCRay *r, const cbvh_ray *in)
{
    r->org_x = in->org[0];
    r->org_y = in->org[1];
    r->org_z = in->org[2];
    r->tnear = in->tmin;
    r->dir_x = in->dir[0];
    r->dir_y = in->dir[1];
    r->dir_z = in->dir[2];
    r->time = 0.0f;
    r->tfar = in->tmax;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

/* Embree's answer for one ray in cbvh's form. */
static void store_hit(cbvh_hit *h, unsigned geom, unsigned prim, float tfar, float u, float v)
{
    if (geom == RTC_INVALID_GEOMETRY_ID) {
        h->tri = CBVH_NO_HIT;
        h->t = INFINITY;
        h->u = h->v = 0.0f;
    } else {
        h->tri = prim;
        h->t = tfar;
        h->u = u;
        h->v = v;
    }
}

void embree_peer_raycast(const embree_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCScene scene = peer->scene;
    for (size_t i = 0; i < count; i++) {
        struct RTCRayHit rh;
        set_ray(&rh.ray, &rays[i]);
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene, &context, &rh);
        store_hit(&hits[i], rh.hit.geomID, rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v);
    }
}

void embree_peer_occluded(const embree_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCScene scene = peer->scene;
    for (size_t i = 0; i < count; i++) {
        struct RTCRay r;
        set_ray(&r, &rays[i]);
        rtcOccluded1(scene, &context, &r);
        occluded[i] = r.tfar < 0.0f; /* Embree sets tfar to -inf on a hit */
    }
}

/* Loads up to 16 rays into a packet; returns the lanes used and fills `valid`. */
static size_t load_packet(struct RTCRay16 *r, int valid[16], const cbvh_ray *rays, size_t count)
{
    size_t n = count < 16 ? count : 16;
    for (size_t k = 0; k < 16; k++) {
        const cbvh_ray *in = &rays[k < n ? k : 0];
        valid[k] = k < n ? -1 : 0;
        r->org_x[k] = in->org[0];
        r->org_y[k] = in->org[1];
        r->org_z[k] = in->org[2];
        r->tnear[k] = in->tmin;
        r->dir_x[k] = in->dir[0];
        r->dir_y[k] = in->dir[1];
        r->dir_z[k] = in->dir[2];
        r->time[k] = 0.0f;
        r->tfar[k] = in->tmax;
        r->mask[k] = 0xFFFFFFFFu;
        r->id[k] = (unsigned)k;
        r->flags[k] = 0;
    }
    return n;
}

void embree_peer_raycast16(const embree_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRayHit16 rh;
    int valid[16];
    for (size_t i = 0; i < count; i += 16) {
        size_t n = load_packet(&rh.ray, valid, rays + i, count - i);
        for (size_t k = 0; k < 16; k++)
            rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect16(valid, peer->scene, &context, &rh);
        for (size_t k = 0; k < n; k++)
            store_hit(&hits[i + k], rh.hit.geomID[k], rh.hit.primID[k], rh.ray.tfar[k], rh.hit.u[k],
                      rh.hit.v[k]);
    }
}

void embree_peer_occluded16(const embree_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRay16 r;
    int valid[16];
    for (size_t i = 0; i < count; i += 16) {
        size_t n = load_packet(&r, valid, rays + i, count - i);
        rtcOccluded16(valid, peer->scene, &context, &r);
        for (size_t k = 0; k < n; k++)
            occluded[i + k] = r.tfar[k] < 0.0f;
    }
}
