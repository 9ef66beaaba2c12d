/* label_layout.c: places the text labels of scatter-plot markers so none overlap each other or a marker and
 * all stay inside the plot (greedy, leader lines when displaced). */
#include <math.h>

#include "label_layout.h"

/* Rings of candidates around a marker before the area-wide search, and candidates per ring. */
#define RINGS 6
#define RING_ANGLES 16
#define TWO_PI 6.283185307179586

int label_boxes_overlap(const label_box *a, const label_box *b)
{
    return a->x0 < b->x1 && b->x0 < a->x1 && a->y0 < b->y1 && b->y0 < a->y1;
}

int label_box_inside(const label_box *b, const label_box *area)
{
    return b->x0 >= area->x0 && b->x1 <= area->x1 && b->y0 >= area->y0 && b->y1 <= area->y1;
}

typedef struct layout_ctx {
    const label_box *obstacles;
    size_t obstacle_count;
    const label_spot *placed; /* out[0..placed_count), some not placed */
    size_t placed_count;
    label_box area;
    double gap;
} layout_ctx;

/* 1 when a label at box is inside the area and at least gap away from every obstacle and placed label. */
static int is_free(const layout_ctx *c, const label_box *box)
{
    if (!label_box_inside(box, &c->area))
        return 0;
    label_box grown = {box->x0 - c->gap, box->y0 - c->gap, box->x1 + c->gap, box->y1 + c->gap};
    for (size_t i = 0; i < c->obstacle_count; i++)
        if (label_boxes_overlap(&grown, &c->obstacles[i]))
            return 0;
    for (size_t i = 0; i < c->placed_count; i++)
        if (c->placed[i].placed && label_boxes_overlap(&grown, &c->placed[i].box))
            return 0;
    return 1;
}

static label_box box_at(double cx, double cy, double w, double h)
{
    return (label_box){cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2};
}

/* The positions right beside the marker, in order of preference: right, left,
 * above, below, then the four corners. */
static int try_beside(const layout_ctx *c, const label_request *r, double reach, label_box *out)
{
    static const double dirs[8][2] = {{1, 0}, {-1, 0}, {0, -1}, {0, 1}, {1, -1}, {-1, -1}, {1, 1}, {-1, 1}};
    for (int k = 0; k < 8; k++) {
        double cx = r->x + dirs[k][0] * (reach + r->width / 2),
               cy = r->y + dirs[k][1] * (reach + r->height / 2);
        label_box b = box_at(cx, cy, r->width, r->height);
        if (is_free(c, &b)) {
            *out = b;
            return 1;
        }
    }
    return 0;
}

/* Widening rings: the box's centre on an ellipse that clears the marker by `reach`. */
static int try_rings(const layout_ctx *c, const label_request *r, double reach, label_box *out)
{
    for (int ring = 1; ring <= RINGS; ring++) {
        double d = reach + ring * r->height;
        for (int k = 0; k < RING_ANGLES; k++) {
            double a = TWO_PI * k / RING_ANGLES;
            double cx = r->x + cos(a) * (d + r->width / 2), cy = r->y - sin(a) * (d + r->height / 2);
            label_box b = box_at(cx, cy, r->width, r->height);
            if (is_free(c, &b)) {
                *out = b;
                return 1;
            }
        }
    }
    return 0;
}

/* Anywhere in the area on a grid of half a label height, the free box nearest the marker. */
static int try_anywhere(const layout_ctx *c, const label_request *r, label_box *out)
{
    double step = fmax(r->height / 2, 1.0), best = INFINITY;
    for (double y = c->area.y0; y + r->height <= c->area.y1; y += step)
        for (double x = c->area.x0; x + r->width <= c->area.x1; x += step) {
            label_box b = {x, y, x + r->width, y + r->height};
            double dx = x + r->width / 2 - r->x, dy = y + r->height / 2 - r->y, d = dx * dx + dy * dy;
            if (d < best && is_free(c, &b)) {
                best = d;
                *out = b;
            }
        }
    return isfinite(best);
}

size_t label_layout(const label_request *requests, size_t count, const label_box *obstacles,
                    size_t obstacle_count, const label_box *area, double gap, double reach, label_spot *out)
{
    layout_ctx c = {obstacles, obstacle_count, out, 0, *area, gap};
    size_t placed = 0;
    for (size_t i = 0; i < count; i++) {
        const label_request *r = &requests[i];
        label_spot *s = &out[i];
        s->placed = s->leader = 0;
        s->box = (label_box){0, 0, 0, 0};
        if (r->width > 0 && r->height > 0 && isfinite(r->x) && isfinite(r->y)) {
            if (try_beside(&c, r, reach, &s->box))
                s->placed = 1;
            else if (try_rings(&c, r, reach, &s->box) || try_anywhere(&c, r, &s->box))
                s->placed = s->leader = 1;
        }
        placed += (size_t)s->placed;
        c.placed_count = i + 1;
    }
    return placed;
}
