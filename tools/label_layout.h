/* label_layout.h: places the text labels of scatter-plot markers so none overlap each other or a marker and
 * all stay inside the plot (greedy, leader lines when displaced). */
#ifndef CBVH_TOOLS_LABEL_LAYOUT_H
#define CBVH_TOOLS_LABEL_LAYOUT_H

#include <stddef.h>

/* An axis-aligned box in pixels, x0 <= x1 and y0 <= y1. */
typedef struct label_box {
    double x0, y0, x1, y1;
} label_box;

/* One label to place: the marker it belongs to and the label's size. */
typedef struct label_request {
    double x, y;          /* the marker's centre */
    double width, height; /* the label's extent */
} label_request;

/* Where a label went. */
typedef struct label_spot {
    label_box box; /* valid when placed */
    int placed;    /* 0: no free room left inside the area: the caller leaves this label out */
    int leader;    /* 1: the label sits away from its marker: draw a line from the marker to the box */
} label_spot;

/* 1 when the interiors of a and b intersect (boxes that only touch do not). */
int label_boxes_overlap(const label_box *a, const label_box *b);

/* 1 when b lies inside area (edges included). */
int label_box_inside(const label_box *b, const label_box *area);

/* Places the labels in request order (put the most important first): each
 * takes the nearest free candidate position around its marker (beside it
 * first, then on widening rings, then anywhere in the area, nearest first), so
 * that every placed box lies inside `area`, overlaps no other placed box and
 * no obstacle (the markers' boxes, given by the caller), and keeps a `gap` of
 * pixels from them. A label right beside its marker has its nearest edge
 * `reach` pixels from the marker's centre. Fills out[0..count) and returns
 * the number placed. */
size_t label_layout(const label_request *requests, size_t count, const label_box *obstacles,
                    size_t obstacle_count, const label_box *area, double gap, double reach, label_spot *out);

#endif
