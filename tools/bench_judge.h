/* bench_judge.h: whom the double-precision reference sides with where cbvh and a peer answer a shape query
 * differently. */
#ifndef CBVH_TOOLS_BENCH_JUDGE_H
#define CBVH_TOOLS_BENCH_JUDGE_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"
#include "support/reference.h"
#include "support/shapes.h"

/* Whose answer to one query the reference bears out. */
typedef enum bench_side { BENCH_SIDE_NEITHER, BENCH_SIDE_CBVH, BENCH_SIDE_PEER, BENCH_SIDE_BOTH } bench_side;

/* The reference of one mesh: its triangles in double (tools/support/reference.c), and which of them each
 * engine reported for the overlap being judged (one byte per original id). */
typedef struct bench_judge {
    ref_tris tris;
    uint32_t id_count;
    uint8_t *reported[2];                      /* [0]: cbvh, [1]: the peer */
    double overlap_tolerance, sweep_tolerance; /* lengths */
} bench_judge;

/* Reads the file's triangles (original ids below id_count). Overlaps are judged with a tolerance of
 * overlap_tolerance (a length: a triangle within it of the region's boundary may be reported or not),
 * sweeps with sweep_tolerance (a contact counts when it is on the reference's first triangle or within
 * this distance along the motion of the reference's, and a grazing contact, gone once the shape shrinks
 * by overlap_tolerance, may be reported or not). Returns 0 when out of memory. */
int bench_judge_init(bench_judge *j, const cbvh_file *file, uint32_t id_count, double overlap_tolerance,
                     double sweep_tolerance);
void bench_judge_free(bench_judge *j);

/* Marks triangle `tri` as reported by engine `side` (0: cbvh, 1: the peer) for the next
 * bench_judge_overlap; ids out of range are ignored. */
void bench_judge_mark(bench_judge *j, int side, uint32_t tri);

/* The side the reference takes on overlap query q (kind: sphere, capsule or axis-aligned box) between the
 * marked sets: an engine is borne out when it reported every triangle that surely overlaps and none that
 * is surely apart (ref_*_class with the overlap tolerance), by brute force over every triangle. Clears
 * the marks. */
bench_side bench_judge_overlap(bench_judge *j, shape_kind kind, const shape_query *q);

/* The side the reference takes on a ray's closest hit between cbvh's answer and the peer's (tri CBVH_NO_HIT
 * for a miss), with the overlap tolerance as the length that decides (ref_ray_closest's margin, and |t - t'|
 * times |dir|): a miss is borne out when no triangle is surely crossed (margin >= tolerance); a hit when its
 * triangle is crossed (margin >= -tolerance) at its t within the tolerance and no triangle is surely crossed
 * before it by more than the tolerance. By brute force over every triangle. */
bench_side bench_judge_ray(const bench_judge *j, const cbvh_ray *ray, const cbvh_hit *cbvh,
                           const cbvh_hit *peer);

/* The same for a ray's any-hit flags: occluded is borne out when some triangle is crossed within the
 * tolerance (margin >= -tolerance), not occluded when none is surely crossed. */
bench_side bench_judge_occluded(const bench_judge *j, const cbvh_ray *ray, int cbvh, int peer);

/* The side the reference takes on first-hit overlap query q (kind as for bench_judge_overlap) between cbvh's
 * answer and the peer's (count 0: the shape touches nothing; 1: it touches triangle tri): a miss is borne out
 * when no triangle surely overlaps, a hit when its triangle is not surely apart (ref_*_class with the overlap
 * tolerance), by brute force over every triangle. */
bench_side bench_judge_first_hit(const bench_judge *j, shape_kind kind, const shape_query *q,
                                 const shape_answer *cbvh, const shape_answer *peer);

/* The side the reference takes on sweep query q between the first contacts cbvh and the peer found:
 * ref_sweep's first contact, by brute force. A miss is borne out when the shape shrunk by the overlap
 * tolerance misses too; a hit when it is on the reference's first triangle or within the sweep tolerance
 * of its contact along the motion, or, the reference missing, when the shape at the hit's t lies within
 * the overlap tolerance of the hit's triangle. */
bench_side bench_judge_sweep(const bench_judge *j, shape_kind kind, const shape_query *q,
                             const shape_answer *cbvh, const shape_answer *peer);

#endif
