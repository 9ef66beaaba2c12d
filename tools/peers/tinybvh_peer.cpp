// tinybvh_peer.cpp: the tinybvh benchmark peer (BVH8_CPU and BVH4_CPU single rays; --with-tinybvh=DIR).
//
// This file is compiled with AVX2 and FMA (configure's TINYBVH_CXXFLAGS): tinybvh's wide kernels need them,
// and any function here may use them. Callers check the CPU first (peers.h).
#include "config.h"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <new>
#include <vector>

#define TINYBVH_IMPLEMENTATION
#include "tiny_bvh.h"

#include "peers.h"

namespace
{

// Bytes tinybvh holds through its allocation hooks (its build data: the binary and wide trees it converts
// from, kept alive by BVH8_CPU and BVH4_CPU). Each block carries its size in a header one alignment unit
// long.
constexpr size_t hook_alignment = 64;

void *counted_malloc(size_t size, void *user)
{
    if (size == 0)
        return nullptr;
    const size_t total = (size + 2 * hook_alignment - 1) / hook_alignment * hook_alignment;
    char *block = static_cast<char *>(std::aligned_alloc(hook_alignment, total));
    if (!block)
        return nullptr;
    *reinterpret_cast<size_t *>(block) = size;
    static_cast<std::atomic<int64_t> *>(user)->fetch_add(static_cast<int64_t>(size),
                                                         std::memory_order_relaxed);
    return block + hook_alignment;
}

void counted_free(void *ptr, void *user)
{
    if (!ptr)
        return;
    char *block = static_cast<char *>(ptr) - hook_alignment;
    const size_t size = *reinterpret_cast<size_t *>(block);
    static_cast<std::atomic<int64_t> *>(user)->fetch_sub(static_cast<int64_t>(size),
                                                         std::memory_order_relaxed);
    std::free(block);
}

double now_seconds(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// tinybvh's ray from cbvh's. t stays in units of dir (tinybvh's Ray constructor would normalize it). tinybvh
// has no tmin: the ray starts at org + tmin * dir instead, and its t counts from there.
void make_ray(tinybvh::Ray &r, const cbvh_ray *in)
{
    const float t0 = in->tmin;
    r.O = tinybvh::bvhvec3(in->org[0] + t0 * in->dir[0], in->org[1] + t0 * in->dir[1],
                           in->org[2] + t0 * in->dir[2]);
    r.D = tinybvh::bvhvec3(in->dir[0], in->dir[1], in->dir[2]);
    r.rD = tinybvh::tinybvh_rcp(r.D);
    r.mask = RAY_MASK_INTERSECT_ALL;
    r.instIdx = 0;
    r.hit.t = in->tmax - t0;
    r.hit.u = r.hit.v = 0.0f;
    r.hit.prim = CBVH_NO_HIT;
}

} // namespace

struct tinybvh_peer {
    std::atomic<int64_t> hooked{0};
    // The vertices as tinybvh takes them, 16-byte aligned bvhvec4s: it reads each as one (a 12-byte stride
    // would misalign them). Kept while the tree lives, which holds a view of them, though its queries read
    // only its blocks.
    std::vector<tinybvh::bvhvec4> vertices;
    tinybvh::BVH8_CPU *bvh8 = nullptr;
    tinybvh::BVH4_CPU *bvh4 = nullptr;
};

// Both layouts keep their traversal blocks in one array allocated outside the hooks (4 KiB aligned), yet free
// it through the hooks on destruction: the peer frees it itself first.
template <class Tree> static void release(Tree *tree, typename Tree::CacheLine *Tree::*blocks)
{
    if (!tree)
        return;
    std::free(tree->*blocks);
    tree->*blocks = nullptr;
    delete tree;
}

// Builds tree (set before the build, so that the peer frees it when the build throws).
template <class Tree> static void build(tinybvh_peer *p, Tree *&tree, const peer_mesh *mesh)
{
    tinybvh::BVHContext context;
    context.malloc = counted_malloc;
    context.free = counted_free;
    context.userdata = &p->hooked;
    tree = new Tree(context);
    const float *xyz = mesh->positions;
    p->vertices.resize(mesh->vertex_count);
    for (size_t i = 0; i < mesh->vertex_count; i++)
        p->vertices[i] = tinybvh::bvhvec4(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2], 0.0f);
    tinybvh::bvhvec4slice vertices(p->vertices.data(), static_cast<uint32_t>(mesh->vertex_count),
                                   sizeof(tinybvh::bvhvec4));
    tree->BuildHQ(vertices, mesh->indices, static_cast<uint32_t>(mesh->triangle_count));
}

tinybvh_peer *tinybvh_peer_create(const peer_mesh *mesh, tinybvh_layout layout, peer_build_info *info,
                                  char *err, size_t err_size)
{
    if (mesh->triangle_count == 0 || mesh->triangle_count > (1u << 29) || mesh->vertex_count > UINT32_MAX) {
        std::snprintf(err, err_size,
                      "tinybvh: %zu triangles over %zu vertices are outside what its indices reach",
                      mesh->triangle_count, mesh->vertex_count);
        return nullptr;
    }
    tinybvh_peer *p = new (std::nothrow) tinybvh_peer;
    if (!p) {
        std::snprintf(err, err_size, "tinybvh: out of memory");
        return nullptr;
    }
    const double start = now_seconds(CLOCK_MONOTONIC), cpu_start = now_seconds(CLOCK_PROCESS_CPUTIME_ID);
    uint64_t blocks_allocated = 0, blocks_used = 0;
    try {
        if (layout == TINYBVH_BVH8_CPU) {
            build(p, p->bvh8, mesh);
            blocks_allocated = p->bvh8->allocatedBlocks;
            blocks_used = p->bvh8->usedBlocks;
        } else {
            build(p, p->bvh4, mesh);
            blocks_allocated = p->bvh4->allocatedBlocks;
            blocks_used = p->bvh4->usedBlocks;
        }
    } catch (const std::bad_alloc &) {
        std::snprintf(err, err_size, "tinybvh: out of memory building %s",
                      layout == TINYBVH_BVH8_CPU ? "BVH8_CPU" : "BVH4_CPU");
        tinybvh_peer_destroy(p);
        return nullptr;
    }
    info->seconds = now_seconds(CLOCK_MONOTONIC) - start;
    info->cpu_seconds = now_seconds(CLOCK_PROCESS_CPUTIME_ID) - cpu_start;
    // A block is one 64-byte cache line of nodes or leaf triangles.
    const int64_t hooked = p->hooked.load(std::memory_order_relaxed);
    info->memory_bytes = 64u * blocks_allocated + (hooked > 0 ? static_cast<uint64_t>(hooked) : 0u);
    info->traversed_bytes = 64u * blocks_used;
    // The leaves hold their own copies of the triangles: queries read no mesh array.
    info->mesh_bytes = 0;
    return p;
}

void tinybvh_peer_destroy(tinybvh_peer *peer)
{
    if (!peer)
        return;
    release(peer->bvh8, &tinybvh::BVH8_CPU::bvh8Data);
    release(peer->bvh4, &tinybvh::BVH4_CPU::bvh4Data);
    delete peer;
}

template <class Tree>
static void raycast(const Tree *tree, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    tinybvh::Ray r;
    for (size_t i = 0; i < count; i++) {
        make_ray(r, &rays[i]);
        tree->Intersect(r);
        cbvh_hit *h = &hits[i];
        if (r.hit.prim == CBVH_NO_HIT) {
            h->tri = CBVH_NO_HIT;
            h->t = INFINITY;
            h->u = h->v = 0.0f;
        } else {
            h->tri = r.hit.prim;
            h->t = rays[i].tmin + r.hit.t;
            h->u = r.hit.u;
            h->v = r.hit.v;
        }
    }
}

template <class Tree> static void occluded(const Tree *tree, const cbvh_ray *rays, size_t count, uint8_t *out)
{
    tinybvh::Ray r;
    for (size_t i = 0; i < count; i++) {
        make_ray(r, &rays[i]);
        out[i] = tree->IsOccluded(r);
    }
}

void tinybvh_peer_raycast(const tinybvh_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits)
{
    if (peer->bvh8)
        raycast(peer->bvh8, rays, count, hits);
    else
        raycast(peer->bvh4, rays, count, hits);
}

void tinybvh_peer_occluded(const tinybvh_peer *peer, const cbvh_ray *rays, size_t count,
                           uint8_t *occluded_out)
{
    if (peer->bvh8)
        occluded(peer->bvh8, rays, count, occluded_out);
    else
        occluded(peer->bvh4, rays, count, occluded_out);
}
