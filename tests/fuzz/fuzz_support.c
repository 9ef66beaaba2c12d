/* fuzz_support.c: guard-page copies, checksum repair and the query invariants every fuzz target and
 * corruption test asserts. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "fuzz_support.h"
#include "le_bytes.h"
#include "support/test_os.h"

/* Header and table offsets, as in lib/common/format.h (the harness stays
 * independent of the library's internals). */
enum {
    HDR_SIZE = 128,
    HDR_SECTION_COUNT = 24,
    HDR_TABLE_CRC = 28,
    HDR_ORIGINAL_TRIS = 52,
    HDR_FILE_SIZE = 104,
    HDR_CRC = 124,
    ENTRY_SIZE = 40,
    ENTRY_OFFSET = 8,
    ENTRY_STORED = 16,
    ENTRY_CRC = 32,
    MAX_SECTIONS = 16
};

void fuzz_fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("cbvh invariant broken: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    abort();
}

void guard_copy(guard_buffer *g, const void *data, size_t size)
{
    size_t page = test_page_size();
    size_t data_pages = (size + page - 1) / page;
    if (data_pages == 0)
        data_pages = 1;
    g->map_size = (data_pages + 1) * page;
    g->map = test_pages_map(g->map_size);
    if (!g->map)
        fuzz_fail("cannot map %zu bytes", g->map_size);
    uint8_t *guard = (uint8_t *)g->map + data_pages * page;
    if (test_pages_protect_none(guard, page) != 0)
        fuzz_fail("cannot protect the guard page");
    g->data = guard - size;
    g->size = size;
    if (size)
        memcpy(g->data, data, size);
}

void guard_release(guard_buffer *g)
{
    if (g->map)
        test_pages_unmap(g->map, g->map_size);
    memset(g, 0, sizeof *g);
}

static uint32_t crc_of(const uint8_t *p, uint64_t n)
{
    uLong c = crc32(0L, Z_NULL, 0);
    while (n > 0) { /* zlib takes uInt lengths */
        uInt chunk = n > 0x40000000u ? 0x40000000u : (uInt)n;
        c = crc32(c, p, chunk);
        p += chunk;
        n -= chunk;
    }
    return (uint32_t)c;
}

void fuzz_repair_checksums(uint8_t *bytes, size_t size)
{
    if (size < HDR_SIZE)
        return;
    le_put_u64(bytes + HDR_FILE_SIZE, size);
    uint32_t count = le_get_u32(bytes + HDR_SECTION_COUNT);
    if (count > MAX_SECTIONS)
        count = MAX_SECTIONS;
    if ((size - HDR_SIZE) / ENTRY_SIZE < count)
        count = (uint32_t)((size - HDR_SIZE) / ENTRY_SIZE);
    for (uint32_t i = 0; i < count; i++) {
        uint8_t *e = bytes + HDR_SIZE + (size_t)i * ENTRY_SIZE;
        uint64_t off = le_get_u64(e + ENTRY_OFFSET), stored = le_get_u64(e + ENTRY_STORED);
        if (off <= size && stored <= size - off)
            le_put_u32(e + ENTRY_CRC, crc_of(bytes + off, stored));
    }
    le_put_u32(bytes + HDR_TABLE_CRC, crc_of(bytes + HDR_SIZE, (uint64_t)count * ENTRY_SIZE));
    le_put_u32(bytes + HDR_CRC, crc_of(bytes, HDR_CRC));
}

void fuzz_check_error(cbvh_result r, const cbvh_error *err)
{
    FUZZ_CHECK(r != CBVH_OK && r <= CBVH_ERROR_LIMIT, "unknown result code %d", (int)r);
    FUZZ_CHECK(err->code == r, "error code %d differs from the returned %d", (int)err->code, (int)r);
    FUZZ_CHECK(memchr(err->message, 0, sizeof err->message) != NULL, "error message not terminated");
    FUZZ_CHECK(err->message[0] != 0, "empty error message for code %d", (int)r);
    FUZZ_CHECK(strlen(cbvh_result_string(r)) > 0, "empty result string");
}

/* ---- double-precision geometry for the checks ---- */

typedef struct dvec {
    double x, y, z;
} dvec;
static dvec dv(const float p[3])
{
    dvec r = {p[0], p[1], p[2]};
    return r;
}
static dvec dsub(dvec a, dvec b)
{
    dvec r = {a.x - b.x, a.y - b.y, a.z - b.z};
    return r;
}
static dvec dadd(dvec a, dvec b)
{
    dvec r = {a.x + b.x, a.y + b.y, a.z + b.z};
    return r;
}
static dvec dmul(dvec a, double s)
{
    dvec r = {a.x * s, a.y * s, a.z * s};
    return r;
}
static double ddot(dvec a, dvec b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static double dlen(dvec a)
{
    return sqrt(ddot(a, a));
}
static double dmaxabs(dvec a)
{
    return fmax(fabs(a.x), fmax(fabs(a.y), fabs(a.z)));
}
static int dfinite(dvec a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}

static dvec closest_on_segment(dvec p, dvec a, dvec b)
{
    dvec ab = dsub(b, a);
    double len2 = ddot(ab, ab), t = len2 > 0 ? ddot(dsub(p, a), ab) / len2 : 0;
    return dadd(a, dmul(ab, t < 0 ? 0 : t > 1 ? 1 : t));
}

static dvec dcross(dvec a, dvec b)
{
    dvec r = {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    return r;
}

/* Closest point on triangle abc to p: the projection onto the plane when it
 * falls inside (edge-side tests, which stay accurate on slivers where the
 * barycentric region formulas cancel catastrophically), else the closest
 * point on the three edges (also covers degenerate triangles). */
static dvec closest_on_triangle(dvec p, dvec a, dvec b, dvec c)
{
    /* the normal from the two shorter edges, at the vertex opposite the
     * longest: on a sliver the long edges' differences round at the scale of
     * the short one and tilt the plane (a rotation keeps the orientation) */
    double la = dlen(dsub(c, b)), lb = dlen(dsub(a, c)), lc = dlen(dsub(b, a));
    if (lb > la && lb >= lc) {
        dvec t = a;
        a = b;
        b = c;
        c = t;
    } else if (lc > la && lc > lb) {
        dvec t = a;
        a = c;
        c = b;
        b = t;
    }
    dvec n = dcross(dsub(b, a), dsub(c, a));
    double nn = ddot(n, n);
    if (nn > 0 && isfinite(nn)) {
        dvec q = dsub(p, dmul(n, ddot(dsub(p, a), n) / nn));
        if (ddot(dcross(dsub(b, a), dsub(q, a)), n) >= 0 && ddot(dcross(dsub(c, b), dsub(q, b)), n) >= 0 &&
            ddot(dcross(dsub(a, c), dsub(q, c)), n) >= 0)
            return q;
    }
    dvec e[3] = {closest_on_segment(p, a, b), closest_on_segment(p, b, c), closest_on_segment(p, c, a)};
    int best = 0;
    for (int i = 1; i < 3; i++)
        if (dlen(dsub(p, e[i])) < dlen(dsub(p, e[best])))
            best = i;
    return e[best];
}

/* ---- the query sweep ---- */

typedef struct check_ctx {
    const cbvh_file *f;
    cbvh_file_info info;
    uint32_t original_count;
    double scale; /* magnitude of the file's coordinates, for tolerances */
    int strict;
    uint64_t rng;
    size_t queries;
} check_ctx;

static double unit(check_ctx *c)
{
    uint64_t z = (c->rng += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

/* A point in the file's bounds grown by `grow` of the extent on each side. */
static void random_point(check_ctx *c, double grow, float out[3])
{
    for (int a = 0; a < 3; a++) {
        double lo = c->info.bounds_min[a], hi = c->info.bounds_max[a];
        double pad = (hi - lo) * grow + 1e-3 * (fabs(lo) + fabs(hi)) + 1e-6;
        out[a] = (float)(lo - pad + unit(c) * (hi - lo + 2 * pad));
    }
}

static int triangle_of(const check_ctx *c, uint32_t tri, dvec v[3])
{
    float a[3], b[3], d[3];
    if (!cbvh_file_get_triangle(c->f, tri, a, b, d))
        return 0;
    v[0] = dv(a);
    v[1] = dv(b);
    v[2] = dv(d);
    return 1;
}

static int ray_valid(const cbvh_ray *r)
{
    for (int a = 0; a < 3; a++)
        if (!isfinite(r->org[a]) || !isfinite(r->dir[a]))
            return 0;
    if (r->dir[0] == 0 && r->dir[1] == 0 && r->dir[2] == 0)
        return 0;
    return !isnan(r->tmin) && !isnan(r->tmax) && isfinite(r->tmin) && r->tmin >= 0 && r->tmin <= r->tmax;
}

static void check_hit(check_ctx *c, const cbvh_ray *r, const cbvh_hit *h, int got, const char *what)
{
    if (!got) {
        FUZZ_CHECK(h->tri == CBVH_NO_HIT, "%s: miss with tri %u", what, h->tri);
        return;
    }
    FUZZ_CHECK(ray_valid(r), "%s: invalid ray hit triangle %u", what, h->tri);
    dvec v[3];
    FUZZ_CHECK(triangle_of(c, h->tri, v), "%s: hit triangle id %u out of range", what, h->tri);
    FUZZ_CHECK(h->t >= r->tmin && h->t <= r->tmax, "%s: t %.9g outside [%.9g, %.9g]", what, h->t, r->tmin,
               r->tmax);
    const double eps = 1e-4;
    FUZZ_CHECK(h->u >= -eps && h->v >= -eps && (double)h->u + h->v <= 1 + eps,
               "%s: barycentrics u %.9g v %.9g outside the triangle", what, h->u, h->v);
    dvec o = dv(r->org), d = dv(r->dir);
    dvec p = dadd(o, dmul(d, h->t));
    dvec q = dadd(dmul(v[0], 1.0 - h->u - h->v), dadd(dmul(v[1], h->u), dmul(v[2], h->v)));
    double mag = fmax(fmax(dmaxabs(o), dmaxabs(p)), fmax(dmaxabs(v[0]), fmax(dmaxabs(v[1]), dmaxabs(v[2]))));
    if (!dfinite(p) || !dfinite(q))
        return;
    /* the barycentric point must lie on the ray's line and the ray point on
     * the triangle's plane: both stay well conditioned for grazing rays,
     * where t itself is not (a ray in the plane hits anywhere along it) */
    double line_gap = dlen(dcross(dsub(q, o), d)) / dlen(d);
    dvec n = dcross(dsub(v[1], v[0]), dsub(v[2], v[0]));
    double plane_gap = dlen(n) > 0 ? fabs(ddot(dsub(p, v[0]), n)) / dlen(n) : 0;
    /* barycentrics lose accuracy as 1/cos of the angle between ray and normal:
     * a ray in the triangle's plane sees it as a segment */
    double cosine = dlen(n) > 0 ? fabs(ddot(d, n)) / (dlen(d) * dlen(n)) : 0;
    /* a fixed tolerance at every aspect: u, v come from the hit point in
     * double since finding F6 was fixed */
    FUZZ_CHECK(line_gap * cosine <= 1e-3 * mag + 1e-30 && plane_gap <= 1e-3 * mag + 1e-30,
               "%s: tri %u t %.9g u %.9g v %.9g: barycentric point %.3g off the ray, ray point %.3g off the "
               "plane (scale %.3g)",
               what, h->tri, h->t, h->u, h->v, line_gap, plane_gap, mag);
}

/* The boxes a walk tests when it visits every node once (stats count box tests): binary, one per node;
 * wide4, one per used slot (every node but the root fills one, every leaf one, so at most one per
 * triangle; at most four per node) and the root's; both, one more for the box holding the first ones,
 * which a ray from outside the mesh's bounds is tested against before any walk (cbvh.h). */
static uint64_t box_limit(const cbvh_file_info *in)
{
    if (in->layout != CBVH_LAYOUT_WIDE4)
        return in->node_count + 1u;
    const uint64_t slots = (uint64_t)in->node_count - 1u + in->triangle_count, cap = 4ull * in->node_count;
    return (slots < cap ? slots : cap) + 2u;
}

/* Counts the candidates of a query whose filter rejects every one. */
typedef struct fuzz_hits {
    size_t count;
} fuzz_hits;

static cbvh_filter_result fuzz_collect(void *user, const cbvh_hit_record *hit)
{
    (void)hit;
    ((fuzz_hits *)user)->count++;
    return CBVH_FILTER_REJECT;
}

static const char *traversal_name[4] = {"sorted", "stackless", "unsorted", "distance"};

/* One ray through every ray query; `strict` compares them with each other. */
static void check_ray(check_ctx *c, const cbvh_ray *r)
{
    cbvh_hit hits[4];
    int got[4];
    for (int t = 0; t < 4; t++) {
        memset(&hits[t], 0x5A, sizeof hits[t]);
        cbvh_query_stats st = {0, 0};
        got[t] = cbvh_raycast(c->f, r, (cbvh_traversal)t, &hits[t], &st);
        FUZZ_CHECK(got[t] == 0 || got[t] == 1, "raycast returned %d", got[t]);
        check_hit(c, r, &hits[t], got[t], traversal_name[t]);
        FUZZ_CHECK(st.nodes_visited <= box_limit(&c->info),
                   "%s: %llu box tests for %u nodes (a node visited twice)", traversal_name[t],
                   (unsigned long long)st.nodes_visited, c->info.node_count);
        int occ = cbvh_occluded(c->f, r, (cbvh_traversal)t, NULL);
        FUZZ_CHECK(occ == 0 || occ == 1, "occluded returned %d", occ);
        if (!ray_valid(r))
            FUZZ_CHECK(!got[t] && !occ, "%s: invalid ray reported a hit", traversal_name[t]);
        if (c->strict)
            FUZZ_CHECK(occ == got[0], "%s: occluded %d but raycast %d", traversal_name[t], occ, got[0]);
        c->queries += 2;
    }
    /* with options: no culling or filter answers as the plain raycast; with culling, a filter rejecting
     * every candidate leaves a miss and sees at most one candidate per triangle */
    cbvh_query_options q;
    cbvh_query_options_init(&q, sizeof q);
    cbvh_hit_record rec;
    const cbvh_result qr = cbvh_raycast_with(c->f, r, &q, &rec, NULL);
    FUZZ_CHECK(qr == (ray_valid(r) ? CBVH_OK : CBVH_ERROR_INVALID_ARGUMENT), "raycast_with returned %d",
               (int)qr);
    FUZZ_CHECK(rec.tri == hits[0].tri && (!got[0] || rec.t == hits[0].t),
               "raycast_with differs from raycast");
    fuzz_hits all = {0};
    q.filter = fuzz_collect;
    q.filter_user = &all;
    q.cull = CBVH_CULL_BACK;
    cbvh_raycast_with(c->f, r, &q, &rec, NULL);
    FUZZ_CHECK(rec.tri == CBVH_NO_HIT && all.count <= c->info.triangle_count,
               "all hits: %zu candidates for %u triangles, answer %u", all.count, c->info.triangle_count,
               rec.tri);
    c->queries += 2;
    cbvh_hit sh;
    uint8_t socc = 0x77;
    memset(&sh, 0x5A, sizeof sh);
    cbvh_raycast_stream(c->f, r, 1, &sh, NULL);
    cbvh_occluded_stream(c->f, r, 1, &socc, NULL);
    check_hit(c, r, &sh, sh.tri != CBVH_NO_HIT, "stream");
    FUZZ_CHECK(socc == 0 || socc == 1, "occluded stream wrote %u", socc);
    /* the same ray through a batch in caller scratch (odd address): the same answer */
    static _Alignas(64) uint8_t scratch[16384];
    cbvh_hit ssh;
    uint8_t ssocc = 0x77;
    cbvh_raycast_stream_scratch(c->f, r, 1, &ssh, NULL, scratch + 1, sizeof scratch - 1);
    cbvh_occluded_stream_scratch(c->f, r, 1, &ssocc, NULL, scratch + 1, sizeof scratch - 1);
    FUZZ_CHECK(ssh.tri == sh.tri && (sh.tri == CBVH_NO_HIT || ssh.t == sh.t) && ssocc == socc,
               "stream in scratch differs (tri %u t %.9g occ %u vs tri %u t %.9g occ %u)", ssh.tri, ssh.t,
               ssocc, sh.tri, sh.t, socc);
    c->queries += 4;
    if (!c->strict)
        return;
    for (int t = 1; t < 4; t++) {
        FUZZ_CHECK(got[t] == got[0], "%s and sorted disagree: hit %d vs %d", traversal_name[t], got[t],
                   got[0]);
        if (got[0])
            FUZZ_CHECK(hits[t].t == hits[0].t, "%s t %.9g, sorted t %.9g", traversal_name[t], hits[t].t,
                       hits[0].t);
    }
    FUZZ_CHECK((sh.tri != CBVH_NO_HIT) == got[0] && (!got[0] || sh.t == hits[0].t),
               "stream differs from raycast (tri %u t %.9g vs tri %u t %.9g)", sh.tri, sh.t, hits[0].tri,
               hits[0].t);
    FUZZ_CHECK(socc == got[0], "occluded stream %d but raycast %d", socc, got[0]);
}

/* Batched rays: each stream answer must match the same ray cast alone. */
static void check_stream_batch(check_ctx *c, const cbvh_ray *rays, size_t n)
{
    cbvh_hit hits[64];
    uint8_t occ[64];
    cbvh_raycast_stream(c->f, rays, n, hits, NULL);
    cbvh_occluded_stream(c->f, rays, n, occ, NULL);
    c->queries += 2 * n;
    for (size_t i = 0; i < n; i++) {
        check_hit(c, &rays[i], &hits[i], hits[i].tri != CBVH_NO_HIT, "stream batch");
        FUZZ_CHECK(occ[i] <= 1, "occluded stream wrote %u", occ[i]);
        if (c->strict) {
            cbvh_hit one;
            int got = cbvh_raycast(c->f, &rays[i], CBVH_TRAVERSAL_SORTED, &one, NULL);
            FUZZ_CHECK(got == (hits[i].tri != CBVH_NO_HIT) && (!got || one.t == hits[i].t),
                       "stream batch ray %zu differs from its raycast", i);
            FUZZ_CHECK(occ[i] == got, "occluded stream ray %zu: %u, raycast %d", i, occ[i], got);
        }
    }
}

/* The contact point must lie on the triangle, at every coordinate magnitude
 * since finding F5 was fixed. */
static void check_sweep_hit(check_ctx *c, const cbvh_sweep_hit *h, const char *what)
{
    dvec v[3];
    FUZZ_CHECK(triangle_of(c, h->tri, v), "%s: triangle id %u out of range", what, h->tri);
    FUZZ_CHECK(h->t >= 0 && h->t <= 1, "%s: t %.9g outside [0,1]", what, h->t);
    dvec n = dv(h->normal), p = dv(h->point);
    FUZZ_CHECK(dfinite(n) && fabs(dlen(n) - 1) < 1e-3, "%s: normal (%g %g %g) not of unit length", what, n.x,
               n.y, n.z);
    if (!dfinite(p))
        return;
    double mag = fmax(dmaxabs(p), fmax(dmaxabs(v[0]), fmax(dmaxabs(v[1]), dmaxabs(v[2]))));
    double gap = dlen(dsub(p, closest_on_triangle(p, v[0], v[1], v[2])));
    /* the shapes are sized from the file's extent, so the contact point is
     * computed from coordinates of that magnitude: a tiny triangle in a huge
     * file gets the file's precision, not its own */
    if (c->strict)
        FUZZ_CHECK(gap <= 1e-4 * fmax(mag, c->scale) + 1e-30, "%s: contact point %.3g off triangle %u", what,
                   gap, h->tri);
}

/* Sweeps: ids, t and normals always; with strict, the contact distance, and
 * radius 0 against the raycast. */
static void check_sweeps(check_ctx *c)
{
    float center[3], target[3], delta[3], p1[3], half[3];
    random_point(c, 0.5, center);
    random_point(c, 0.0, target);
    double ext = 0;
    for (int a = 0; a < 3; a++) {
        delta[a] = target[a] - center[a];
        ext = fmax(ext, (double)c->info.bounds_max[a] - c->info.bounds_min[a]);
        p1[a] = (float)(center[a] + (unit(c) - 0.5) * 0.2 * ext);
        half[a] = (float)(unit(c) * 0.05 * ext);
    }
    float radius = (float)(unit(c) * 0.05 * ext);
    cbvh_sweep_hit h;
    if (cbvh_sweep_sphere(c->f, center, radius, delta, &h)) {
        check_sweep_hit(c, &h, "sphere sweep");
        if (c->strict && isfinite(h.point[0])) {
            dvec at = dadd(dv(center), dmul(dv(delta), h.t));
            double dist = dlen(dsub(at, dv(h.point))), tol = 1e-4 * fmax(c->scale, dmaxabs(at)) + 1e-30;
            FUZZ_CHECK(dist <= radius + tol, "sphere sweep: contact %.9g from the center, radius %.9g", dist,
                       radius);
            if (h.t > 0)
                FUZZ_CHECK(dist >= radius - tol, "sphere sweep at t %.9g: contact %.9g inside radius %.9g",
                           h.t, dist, radius);
        }
    }
    if (cbvh_sweep_capsule(c->f, center, p1, radius, delta, &h))
        check_sweep_hit(c, &h, "capsule sweep");
    if (cbvh_sweep_box(c->f, center, half, delta, &h))
        check_sweep_hit(c, &h, "box sweep");
    c->queries += 3;

    /* an oriented box (cbvh_sweep_with): the record as a sweep hit, a finite depth >= 0 only at t = 0 */
    cbvh_shape box;
    memset(&box, 0, sizeof box);
    box.kind = CBVH_SHAPE_BOX;
    for (int a = 0; a < 3; a++) {
        box.center[a] = center[a];
        box.half_extent[a] = half[a];
        box.rotation[a] = (float)(unit(c) - 0.5);
    }
    box.rotation[3] = (float)unit(c);
    cbvh_sweep_record rec;
    if (cbvh_sweep_with(c->f, &box, delta, NULL, &rec) == CBVH_OK && rec.tri != CBVH_NO_HIT) {
        cbvh_sweep_hit as_hit = {rec.tri,
                                 rec.t,
                                 {rec.point[0], rec.point[1], rec.point[2]},
                                 {rec.normal[0], rec.normal[1], rec.normal[2]}};
        check_sweep_hit(c, &as_hit, "oriented box sweep");
        FUZZ_CHECK(isfinite(rec.depth) && rec.depth >= 0 && (rec.t == 0 || rec.depth == 0),
                   "oriented box sweep: depth %.9g at t %.9g", rec.depth, rec.t);
    }
    size_t n_over = 0;
    uint32_t over[8];
    int more_over = 0;
    if (cbvh_overlap_with(c->f, &box, NULL, 0, over, 8, &n_over, &more_over) == CBVH_OK)
        FUZZ_CHECK(n_over <= 8 && (more_over == 0 || n_over == 8),
                   "oriented box overlap: %zu written, more %d", n_over, more_over);
    c->queries += 2;

    /* invalid shapes miss */
    float bad_radius = -1.0f, nan_center[3] = {NAN, 0, 0};
    FUZZ_CHECK(!cbvh_sweep_sphere(c->f, center, bad_radius, delta, &h), "negative radius sweep hit");
    FUZZ_CHECK(!cbvh_sweep_sphere(c->f, nan_center, radius, delta, &h), "NaN center sweep hit");
    FUZZ_CHECK(!cbvh_sweep_capsule(c->f, center, nan_center, radius, delta, &h), "NaN capsule sweep hit");
    c->queries += 3;

    if (!c->strict)
        return;
    /* a sphere of radius 0 is a ray from center along delta with t in [0,1] */
    cbvh_ray r = {{center[0], center[1], center[2]}, 0.0f, {delta[0], delta[1], delta[2]}, 1.0f};
    cbvh_hit rh;
    int rgot = cbvh_raycast(c->f, &r, CBVH_TRAVERSAL_SORTED, &rh, NULL);
    int sgot = cbvh_sweep_sphere(c->f, center, 0.0f, delta, &h);
    c->queries += 2;
    FUZZ_CHECK(rgot == sgot, "radius-0 sweep %d but raycast %d", sgot, rgot);
    if (rgot)
        FUZZ_CHECK(fabs((double)h.t - rh.t) <= 1e-4, "radius-0 sweep t %.9g, raycast t %.9g", h.t, rh.t);
}

typedef struct overlap_log {
    uint32_t ids[4096];
    size_t count;
    int stop_after;
} overlap_log;

static int log_overlap(void *user, uint32_t tri)
{
    overlap_log *l = user;
    if (l->count < 4096)
        l->ids[l->count] = tri;
    l->count++;
    return l->stop_after > 0 && (int)l->count >= l->stop_after;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* Checks one overlap answer: ids valid and unique, the capped `out` copy a
 * prefix of the callback's list, early stop honoured. Returns the sorted log. */
static void check_overlap_answer(check_ctx *c, overlap_log *log, size_t n, const uint32_t *out, size_t out_n,
                                 const char *what)
{
    FUZZ_CHECK(n == log->count, "%s: returned %zu, callback saw %zu", what, n, log->count);
    size_t kept = log->count < 4096 ? log->count : 4096;
    for (size_t i = 0; i < kept; i++) {
        dvec v[3];
        FUZZ_CHECK(triangle_of(c, log->ids[i], v), "%s: triangle id %u out of range", what, log->ids[i]);
    }
    for (size_t i = 0; i < out_n; i++)
        FUZZ_CHECK(out[i] == log->ids[i], "%s: out[%zu] %u differs from the callback's %u", what, i, out[i],
                   log->ids[i]);
    qsort(log->ids, kept, sizeof log->ids[0], cmp_u32);
    for (size_t i = 1; i < kept; i++)
        FUZZ_CHECK(log->ids[i] != log->ids[i - 1], "%s: triangle %u reported twice", what, log->ids[i]);
}

static int sorted_has(const overlap_log *log, uint32_t tri)
{
    size_t kept = log->count < 4096 ? log->count : 4096;
    return bsearch(&tri, log->ids, kept, sizeof tri, cmp_u32) != NULL;
}

static void check_overlaps(check_ctx *c)
{
    float a[3], b[3], lo[3], hi[3];
    random_point(c, 0.1, a);
    random_point(c, 0.1, b);
    for (int k = 0; k < 3; k++) {
        lo[k] = fminf(a[k], b[k]);
        hi[k] = fmaxf(a[k], b[k]);
    }
    /* keep boxes small so the answer fits the log */
    double ext = 0;
    for (int k = 0; k < 3; k++)
        ext = fmax(ext, (double)c->info.bounds_max[k] - c->info.bounds_min[k]);
    for (int k = 0; k < 3; k++)
        if ((double)hi[k] - lo[k] > 0.3 * ext)
            hi[k] = (float)(lo[k] + 0.3 * ext);

    static overlap_log log; /* large: keep it off the fuzzer's stack */
    uint32_t out[8];
    memset(&log, 0, sizeof log);
    size_t n = cbvh_overlap_box(c->f, lo, hi, log_overlap, &log, NULL, 0);
    check_overlap_answer(c, &log, n, NULL, 0, "box overlap");
    size_t total = log.count;
    overlap_log capped;
    memset(&capped, 0, sizeof capped);
    size_t m = cbvh_overlap_box(c->f, lo, hi, log_overlap, &capped, out, 8);
    FUZZ_CHECK(m == (total < 8 ? total : 8), "box overlap into 8 slots returned %zu of %zu", m, total);
    check_overlap_answer(c, &capped, m, out, m, "capped box overlap");
    memset(&capped, 0, sizeof capped);
    capped.stop_after = 1;
    m = cbvh_overlap_box(c->f, lo, hi, log_overlap, &capped, NULL, 0);
    FUZZ_CHECK(m == (total ? 1u : 0u), "box overlap stopped at the first: returned %zu of %zu", m, total);
    /* in pages of 8: the first page is the capped query's, and the pages add up to the whole set */
    size_t paged = 0;
    for (int more = 1, page = 0; more; page++) {
        const size_t k = cbvh_overlap_box_from(c->f, lo, hi, paged, out, 8, &more);
        FUZZ_CHECK(k <= 8 && paged + k <= total && (more ? k == 8 : 1),
                   "box overlap page %d: %zu at %zu of %zu", page, k, paged, total);
        FUZZ_CHECK(page > 0 || k == (total < 8 ? total : 8), "first box overlap page: %zu of %zu", k, total);
        paged += k;
        if (paged >= total)
            FUZZ_CHECK(!more, "box overlap pages: more after all %zu", total);
    }
    FUZZ_CHECK(paged == total, "box overlap pages gave %zu of %zu", paged, total);
    c->queries += 4;

    float center[3];
    random_point(c, 0.1, center);
    float radius = (float)(unit(c) * 0.15 * ext);
    overlap_log slog;
    memset(&slog, 0, sizeof slog);
    n = cbvh_overlap_sphere(c->f, center, radius, log_overlap, &slog, NULL, 0);
    check_overlap_answer(c, &slog, n, NULL, 0, "sphere overlap");
    c->queries++;
    /* a capsule from the sphere's center: it holds the ball, so it reports at least the ball's triangles */
    float tip[3];
    random_point(c, 0.1, tip);
    for (int k = 0; k < 3;
         k++) { /* in double: the difference of two floats near FLT_MAX overflows in float */
        tip[k] = (float)((double)center[k] + 0.3 * ((double)tip[k] - center[k]));
        if (!isfinite(tip[k])) /* 0.7 center + 0.3 point: finite unless rounding met FLT_MAX */
            tip[k] = center[k];
    }
    static overlap_log clog;
    memset(&clog, 0, sizeof clog);
    n = cbvh_overlap_capsule(c->f, center, tip, radius, log_overlap, &clog, NULL, 0);
    check_overlap_answer(c, &clog, n, NULL, 0, "capsule overlap");
    if (slog.count < 4096 && clog.count < 4096)
        for (size_t i = 0; i < slog.count; i++)
            FUZZ_CHECK(sorted_has(&clog, slog.ids[i]), "capsule overlap misses triangle %u of its end ball",
                       slog.ids[i]);
    /* the capsule's contacts: as many as its overlaps, each with a depth >= 0 and a unit normal */
    size_t contacts = 0;
    for (int more = 1; more;) {
        cbvh_contact page[8];
        const size_t k = cbvh_contacts_capsule(c->f, center, tip, radius, contacts, page, 8, &more);
        for (size_t j = 0; j < k; j++) {
            dvec v[3];
            const double nl = sqrt((double)page[j].normal[0] * page[j].normal[0] +
                                   (double)page[j].normal[1] * page[j].normal[1] +
                                   (double)page[j].normal[2] * page[j].normal[2]);
            FUZZ_CHECK(page[j].depth >= 0.0f && fabs(nl - 1.0) < 1e-4 && triangle_of(c, page[j].tri, v),
                       "capsule contact: triangle %u depth %g normal length %g", page[j].tri,
                       (double)page[j].depth, nl);
        }
        contacts += k;
        FUZZ_CHECK(k > 0 || !more, "capsule contacts: an empty page with more to come");
    }
    FUZZ_CHECK(contacts == clog.count, "capsule contacts: %zu, overlaps %zu", contacts, clog.count);
    c->queries += 2;

    /* invalid queries report nothing */
    float nan3[3] = {NAN, NAN, NAN};
    FUZZ_CHECK(cbvh_overlap_box(c->f, nan3, hi, NULL, NULL, out, 8) == 0,
               "NaN box overlap reported triangles");
    FUZZ_CHECK(cbvh_overlap_sphere(c->f, center, -1.0f, NULL, NULL, out, 8) == 0,
               "negative radius overlap reported triangles");
    c->queries += 2;

    if (!c->strict || log.count >= 4096 || slog.count >= 4096)
        return;
    /* brute force: reported triangles touch the query (up to rounding), and
     * every triangle that certainly touches it was reported */
    dvec bc = {0.5 * ((double)lo[0] + hi[0]), 0.5 * ((double)lo[1] + hi[1]), 0.5 * ((double)lo[2] + hi[2])};
    double tol = 1e-5 * c->scale + 1e-30;
    /* near FLT_MAX a query bound can round to inf: such a query is invalid
     * and reports nothing, so it makes no "must report" claim */
    int box_valid = 1, sphere_valid = isfinite(radius);
    for (int k = 0; k < 3; k++) {
        box_valid &= isfinite(lo[k]) && isfinite(hi[k]);
        sphere_valid &= isfinite(center[k]);
    }
    for (uint32_t t = 0; t < c->original_count; t++) {
        dvec v[3];
        if (!triangle_of(c, t, v))
            continue;
        dvec cp = closest_on_triangle(bc, v[0], v[1], v[2]);
        double out_by = fmax(fmax(lo[0] - cp.x, cp.x - hi[0]),
                             fmax(fmax(lo[1] - cp.y, cp.y - hi[1]), fmax(lo[2] - cp.z, cp.z - hi[2])));
        int inside_vertex = 0;
        for (int k = 0; k < 3; k++)
            inside_vertex |= v[k].x > lo[0] + tol && v[k].x < hi[0] - tol && v[k].y > lo[1] + tol &&
                             v[k].y < hi[1] - tol && v[k].z > lo[2] + tol && v[k].z < hi[2] - tol;
        if (box_valid && (inside_vertex || out_by < -tol))
            FUZZ_CHECK(sorted_has(&log, t), "box overlap missed triangle %u", t);
        if (sorted_has(&log, t)) {
            int apart = 0;
            double mn[3] = {fmin(v[0].x, fmin(v[1].x, v[2].x)), fmin(v[0].y, fmin(v[1].y, v[2].y)),
                            fmin(v[0].z, fmin(v[1].z, v[2].z))};
            double mx[3] = {fmax(v[0].x, fmax(v[1].x, v[2].x)), fmax(v[0].y, fmax(v[1].y, v[2].y)),
                            fmax(v[0].z, fmax(v[1].z, v[2].z))};
            for (int k = 0; k < 3; k++)
                apart |= mn[k] > hi[k] + tol || mx[k] < lo[k] - tol;
            FUZZ_CHECK(!apart, "box overlap reported triangle %u whose bounds miss the box", t);
        }
        double sd = dlen(dsub(dv(center), closest_on_triangle(dv(center), v[0], v[1], v[2])));
        if (sphere_valid && sd < radius - tol)
            FUZZ_CHECK(sorted_has(&slog, t), "sphere overlap missed triangle %u at distance %.9g < %.9g", t,
                       sd, radius);
        if (sorted_has(&slog, t))
            FUZZ_CHECK(sd <= radius + tol, "sphere overlap reported triangle %u at distance %.9g > %.9g", t,
                       sd, radius);
    }
}

/* A ray from `org` towards `target`, whole line or clipped. */
static cbvh_ray make_ray(const float org[3], const float target[3], float tmin, float tmax)
{
    cbvh_ray r;
    for (int a = 0; a < 3; a++) {
        r.org[a] = org[a];
        r.dir[a] = target[a] - org[a];
    }
    r.tmin = tmin;
    r.tmax = tmax;
    return r;
}

size_t fuzz_check_queries(const cbvh_file *f, const uint8_t *bytes, size_t size, uint64_t seed, int strict)
{
    check_ctx c;
    memset(&c, 0, sizeof c);
    c.f = f;
    c.strict = strict;
    c.rng = seed;
    cbvh_file_get_info(f, &c.info, sizeof c.info);
    c.original_count = size >= 56 ? le_get_u32(bytes + HDR_ORIGINAL_TRIS) : c.info.triangle_count;
    FUZZ_CHECK(c.original_count >= c.info.triangle_count, "original count %u below the triangle count %u",
               c.original_count, c.info.triangle_count);
    for (int a = 0; a < 3; a++)
        c.scale = fmax(c.scale, fmax(fabs(c.info.bounds_min[a]), fabs(c.info.bounds_max[a])));
    /* the cooker drops every triangle of zero area, also those that quantizing
     * the vertices collapses (finding F3), with the same test (float
     * differences and their cross product in double) */
    for (uint32_t t = 0; strict && t < c.original_count; t++) {
        dvec v[3];
        if (triangle_of(&c, t, v)) {
            dvec n = dcross(dsub(v[1], v[0]), dsub(v[2], v[0]));
            FUZZ_CHECK(n.x != 0 || n.y != 0 || n.z != 0, "triangle %u has zero area in the file", t);
        }
    }
    float inf = INFINITY;

    float center[3], corner[3];
    for (int a = 0; a < 3; a++)
        center[a] = (float)(0.5 * ((double)c.info.bounds_min[a] + c.info.bounds_max[a]));
    /* axis rays through the center, from both sides, signed zeros in the other components */
    for (int a = 0; a < 3; a++)
        for (int s = -1; s <= 1; s += 2) {
            cbvh_ray r = {{center[0], center[1], center[2]}, 0.0f, {-0.0f, 0.0f, -0.0f}, inf};
            double ext = (double)c.info.bounds_max[a] - c.info.bounds_min[a];
            r.org[a] = (float)(center[a] - s * (ext + 1.0));
            r.dir[a] = (float)s;
            check_ray(&c, &r);
        }
    /* corner to center */
    for (int k = 0; k < 8; k++) {
        for (int a = 0; a < 3; a++) {
            double lo = c.info.bounds_min[a], hi = c.info.bounds_max[a], pad = 0.25 * (hi - lo) + 1.0;
            corner[a] = (float)((k >> a & 1) ? hi + pad : lo - pad);
        }
        cbvh_ray r = make_ray(corner, center, 0.0f, inf);
        check_ray(&c, &r);
    }
    /* random rays, some clipped, some with tiny or huge direction components */
    cbvh_ray batch[64];
    for (int i = 0; i < 40; i++) {
        float o[3], t[3];
        random_point(&c, 0.5, o);
        random_point(&c, 0.0, t);
        float tmin = (i % 4 == 1) ? (float)(unit(&c) * 0.5) : 0.0f;
        float tmax = (i % 4 == 2) ? (float)(0.5 + unit(&c)) : inf;
        cbvh_ray r = make_ray(o, t, tmin, tmax);
        if (i % 8 == 3)
            r.dir[i % 3] = 1e-40f; /* denormal */
        if (i % 8 == 5)
            r.dir[(i + 1) % 3] *= 1e30f;
        check_ray(&c, &r);
        batch[i] = r;
    }
    /* invalid rays: each must miss everything */
    static const float bad[][8] = {
        {NAN, 0, 0, 0, 1, 0, 0, INFINITY},
        {0, 0, 0, 0, NAN, 1, 0, INFINITY},
        {0, 0, 0, 0, INFINITY, 0, 0, INFINITY},
        {0, 0, 0, 0, 0, 0, 0, INFINITY},
        {0, 0, 0, -1, 1, 0, 0, INFINITY},
        {0, 0, 0, 2, 1, 0, 0, 1},
        {0, 0, 0, 0, 1, 0, 0, NAN},
        {0, INFINITY, 0, 0, 0, 1, 0, INFINITY},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        cbvh_ray r = {
            {bad[i][0], bad[i][1], bad[i][2]}, bad[i][3], {bad[i][4], bad[i][5], bad[i][6]}, bad[i][7]};
        if (i < 3 || i == 7) { /* aim at the mesh so only the invalid component can explain a miss */
            for (int a = 0; a < 3; a++)
                if (isfinite(r.org[a]) && r.org[a] == 0)
                    r.org[a] = corner[a];
        }
        check_ray(&c, &r);
        batch[40 + i] = r;
    }
    check_stream_batch(&c, batch, 40 + sizeof bad / sizeof bad[0]);
    for (int i = 0; i < 4; i++) {
        check_sweeps(&c);
        check_overlaps(&c);
    }
    return c.queries;
}
