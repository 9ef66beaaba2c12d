#!/usr/bin/env python3
"""make_vectors.py: an independent cbvh v1 writer, written from cbvh-format.md alone, that generates the test vectors.

Usage: python3 make_vectors.py [output folder]      (default: the folder of this script)
       python3 make_vectors.py --table              (prints the README's vector table)
       python3 make_vectors.py --am                 (prints fileformat/local.am)

Standard library only (struct, zlib). It does not call the C library: it proves
the spec is implementable and gives the loader files it did not write itself.
The vectors are committed; rerunning this script must reproduce them byte for byte.
"""
import itertools
import math
import os
import struct
import sys
import zlib

MAGIC = b"\x89CBVH\r\n\x1a"
HEADER_SIZE = 128
ENTRY_SIZE = 40
ALIGN = 64
NODES, TRIANGLES, VERTICES, REMAP, MATERIALS = 1, 2, 3, 4, 5
MATERIAL_NAMES = 0x80000006  # ancillary (bit 31)
MATS_UNIFORM = 3  # MATERIALS encoding: one u32 id for every triangle
REMAP_U24 = 2  # REMAP encoding: 3 bytes per id
RAW, ZLIB = 0, 1
TRIS_U16, TRIS_U32, TRIS_DELTA16, TRIS_LOCAL8 = 0, 1, 2, 4  # 3 is reserved (unsupported-encoding)
LOCAL8_BLOCK, LOCAL8_WINDOW = 8, 256
INCOMPAT_W4_DEPTH_FIRST = 0x2
BINARY, WIDE4 = 0, 1  # NODES encodings: the node layouts
VERTS_F32, VERTS_Q16 = 0, 1
LEAF_BIT = 0x80000000

# ---------------------------------------------------------------- binary32 arithmetic


def f32(x):
    """Rounds a Python float (binary64) to binary32. A binary32 sum or product computed
    in binary64 and then rounded is correctly rounded (53 >= 2 x 24 + 2)."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def f32_from_bits(u):
    return struct.unpack("<f", struct.pack("<I", u))[0]


def deq(q, origin, scale):
    """Spec section 1: scaled = (float)q * scale; value = origin + scaled, each rounded to binary32."""
    return f32(origin + f32(float(q) * scale))


def grid_for(lo, hi):
    """Spec section 6: origin = bounds_min, scale = smallest binary32 with deq(65535) >= bounds_max."""
    a, b = 0, 0x7F7FFFFF  # non-negative binary32 bit patterns are ordered like their values
    while a < b:
        mid = (a + b) // 2
        if deq(65535, lo, f32_from_bits(mid)) >= hi:
            b = mid
        else:
            a = mid + 1
    return lo, f32_from_bits(a)


def largest_at_most(v, origin, scale):
    a, b = 0, 65535
    while a < b:
        mid = (a + b + 1) // 2
        if deq(mid, origin, scale) <= v:
            a = mid
        else:
            b = mid - 1
    return a


def smallest_at_least(v, origin, scale, start=0):
    a, b = start, 65535
    while a < b:
        mid = (a + b) // 2
        if deq(mid, origin, scale) >= v:
            b = mid
        else:
            a = mid + 1
    return a


def nearest_q(v, origin, scale):
    up = smallest_at_least(v, origin, scale)
    if up > 0 and v - deq(up - 1, origin, scale) < deq(up, origin, scale) - v:
        return up - 1
    return up


# ---------------------------------------------------------------- cooking


def triangle_area(p):
    u = [p[1][a] - p[0][a] for a in range(3)]
    v = [p[2][a] - p[0][a] for a in range(3)]
    c = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    return math.sqrt(sum(x * x for x in c)) / 2


def box_of(points):
    return [min(p[a] for p in points) for a in range(3)], [max(p[a] for p in points) for a in range(3)]


def surface(lo, hi):
    d = [hi[a] - lo[a] for a in range(3)]
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0]


def build(tris, pos, max_leaf):
    """Median split on the longest centroid axis; returns a nested tree: ('leaf', [tri ids]) or ('node', a, b)
    with the child of larger surface area first (spec section 5)."""
    if len(tris) <= max_leaf:
        return ("leaf", tris)
    cent = {t: [sum(pos[v][a] for v in tri) / 3 for a in range(3)] for t, tri in tris}
    lo, hi = box_of(list(cent.values()))
    axis = max(range(3), key=lambda a: hi[a] - lo[a])
    order = sorted(tris, key=lambda t: (cent[t[0]][axis], t[0]))
    half = len(order) // 2
    a, b = build(order[:half], pos, max_leaf), build(order[half:], pos, max_leaf)
    area = lambda n: surface(*box_of([pos[v] for _, tri in leaves(n) for v in tri]))
    return ("node", a, b) if area(a) >= area(b) else ("node", b, a)


def leaves(n):
    return n[1] if n[0] == "leaf" else leaves(n[1]) + leaves(n[2])


def depth_of(n):
    return 1 if n[0] == "leaf" else 1 + max(depth_of(n[1]), depth_of(n[2]))


def quantized_box(points, grid):
    """Spec section 6: qmin the largest q with deq(q) <= min, qmax the smallest q >= qmin with deq(q) >= max."""
    lo, hi = box_of(points)
    qmin = [largest_at_most(lo[a], *grid[a]) for a in range(3)]
    return qmin, [smallest_at_least(hi[a], *grid[a], qmin[a]) for a in range(3)]


def place_binary(tree, decoded, grid):
    """Spec section 5: the nodes depth-first. Returns (NODES bytes, triangles in cooked order, depth, node count)."""
    nodes, next_tri = [], [0]

    def emit(n):
        qmin, qmax = quantized_box([decoded[v] for _, tri in leaves(n) for v in tri], grid)
        index = len(nodes)
        nodes.append([qmin, qmax, 0])
        if n[0] == "leaf":
            nodes[index][2] = LEAF_BIT | (len(n[1]) - 1) << 27 | next_tri[0]
            next_tri[0] += len(n[1])
            return (qmin, qmax)
        ba = emit(n[1])
        bb = emit(n[2])
        sort = 0
        for k in range(8):
            d = [-1 if k >> a & 1 else 1 for a in range(3)]
            ca = [deq(ba[0][a], *grid[a]) + deq(ba[1][a], *grid[a]) for a in range(3)]
            cb = [deq(bb[0][a], *grid[a]) + deq(bb[1][a], *grid[a]) for a in range(3)]
            if sum((ca[a] - cb[a]) * d[a] for a in range(3)) > 0:
                sort |= 1 << k
        nodes[index][2] = sort << 23 | (len(nodes) - index)
        return (qmin, qmax)

    emit(tree)
    ndata = b"".join(struct.pack("<3H3HI", *q0, *q1, w) for q0, q1, w in nodes)
    return ndata, leaves(tree), depth_of(tree), len(nodes)


W4_ORDERS = list(itertools.permutations(range(4)))  # spec section 5.2's order table: lexicographic


def w4_order(boxes, grid, k):
    """Spec section 5.2: the used slots by increasing dot(qmin + qmax, octant direction k) in binary64 (each
    term exact, summed x, y, z), ties in slot order, then the unused slots; returns its index in the table."""
    def key(s):
        qmin, qmax = boxes[s]
        return sum((-1 if k >> a & 1 else 1) * float(qmin[a] + qmax[a]) * grid[a][1] for a in range(3))
    used = sorted((s for s in range(4) if boxes[s] is not None), key=key)  # sorted() is stable: ties in slot order
    return W4_ORDERS.index(tuple(used + [s for s in range(4) if boxes[s] is None]))


def place_wide4(tree, decoded, grid, depth_first=False):
    """Spec section 5.2: the binary tree collapsed into nodes of up to four slots, allocated breadth first; the
    leaves hold the triangles breadth first (node order), or depth first (INCOMPAT_W4_DEPTH_FIRST).
    Returns (NODES bytes, triangles in cooked order, depth, node count, triangles in depth-first leaf order)."""
    boxes = {}

    def qbox(n):
        if id(n) not in boxes:
            boxes[id(n)] = quantized_box([decoded[v] for _, tri in leaves(n) for v in tri], grid)
        return boxes[id(n)]

    def area(n):
        qmin, qmax = qbox(n)
        return surface([deq(qmin[a], *grid[a]) for a in range(3)], [deq(qmax[a], *grid[a]) for a in range(3)])

    def collapse(n):
        if n[0] == "leaf":
            return [n]  # a mesh whose whole tree is one leaf: a root with that leaf in slot 0
        slots = [n[1], n[2]]
        while len(slots) < 4:
            internal = [s for s in range(len(slots)) if slots[s][0] == "node"]
            if not internal:
                break
            # the first internal slot whose children are both leaves (it would make a node of two slots),
            # else the largest area (ties: the first slot)
            twins = [s for s in internal if slots[s][1][0] == "leaf" and slots[s][2][0] == "leaf"]
            s = twins[0] if twins else max(internal, key=lambda s: (area(slots[s]), -s))
            slots[s:s + 1] = [slots[s][1], slots[s][2]]
        return slots

    queue, index_of, slots_of, first_child_of = [tree], {}, [], []
    depth, level_end = 1, 1
    for i, n in enumerate(queue):
        if i == level_end:
            depth, level_end = depth + 1, len(queue)
        slots = collapse(n)
        slots_of.append(slots)
        first_child_of.append(len(queue))
        for c in slots:
            if c[0] == "node":
                index_of[id(c)] = len(queue)
                queue.append(c)

    def own_triangles(i):
        return [t for c in slots_of[i] if c[0] == "leaf" for t in c[1]]

    def triangles_depth_first(i):
        out = own_triangles(i)
        for c in slots_of[i]:
            if c[0] == "node":
                out += triangles_depth_first(index_of[id(c)])
        return out

    order = depth_first_nodes(slots_of, index_of) if depth_first else range(len(queue))
    first_triangle_of, cooked = {}, []
    for i in order:
        first_triangle_of[i] = len(cooked)
        cooked += own_triangles(i)
    data = b""
    for i, slots in enumerate(slots_of):
        meta = 0
        for s, c in enumerate(slots):
            meta |= 1 << 16 + s
            if c[0] == "node":
                meta |= 1 << 20 + s
            else:
                meta |= (len(c[1]) - 1) << 4 * s
        slot_boxes = [qbox(c) for c in slots] + [None] * (4 - len(slots))
        for k in range(8):
            meta |= w4_order(slot_boxes, grid, k) << 24 + 5 * k
        planes = [[b[p // 3][p % 3] if b else 0 for b in slot_boxes] for p in range(6)]
        data += struct.pack("<24HIIQ", *[q for plane in planes for q in plane], first_child_of[i],
                            first_triangle_of[i], meta)
    return data, cooked, depth, len(queue), triangles_depth_first(0)


def depth_first_nodes(slots_of, index_of):
    """Node indices in depth-first order: a node, then its internal children's subtrees in slot order."""
    out, stack = [], [0]
    while stack:
        i = stack.pop()
        out.append(i)
        stack += reversed([index_of[id(c)] for c in slots_of[i] if c[0] == "node"])
    return out


def number_local8(cooked):
    """Spec section 4, LOCAL8: vertices by first use in cooked order; a block of LOCAL8_BLOCK triangles gives a
    fresh copy to a vertex numbered more than LOCAL8_WINDOW - 3 x LOCAL8_BLOCK below the block's first new id.
    Returns (source vertex of each new id, new ids of each cooked triangle)."""
    latest, order, ctris = {}, [], []
    reach = LOCAL8_WINDOW - 3 * LOCAL8_BLOCK
    for k, (_, tri) in enumerate(cooked):
        if k % LOCAL8_BLOCK == 0:
            window = max(len(order) - reach, 0)
        ids = []
        for v in tri:
            if v not in latest or latest[v] < window:
                latest[v] = len(order)
                order.append(v)
            ids.append(latest[v])
        ctris.append(ids)
    return order, ctris


def local8_bytes(ctris):
    """Blocks of LOCAL8_BLOCK triangles: u32 base (the block's smallest id), then 3 u8 offsets a triangle."""
    out = b""
    for b in range(0, len(ctris), LOCAL8_BLOCK):
        block = ctris[b:b + LOCAL8_BLOCK]
        base = min(v for t in block for v in t)
        offsets = [v - base for t in block for v in t] + [0] * (3 * (LOCAL8_BLOCK - len(block)))
        out += struct.pack("<I", base) + bytes(offsets)
    return out


def cook(positions, triangles, max_leaf=4, vertex_format=VERTS_F32, tri_encoding=None, keep_remap=True,
         materials=None, remap_encoding=None, material_encoding=None, codec=RAW, compat_flags=0, layout=BINARY,
         depth_first=False):
    """Returns (header fields, section list) for a mesh, following the spec's cooking rules (as they were
    before LOCAL8 and depth-first wide4 leaves unless asked: the older vectors keep their bytes)."""
    kept = [(i, t) for i, t in enumerate(triangles) if triangle_area([positions[v] for v in t]) > 0]
    tree = build(kept, positions, max_leaf)
    lo, hi = box_of([positions[v] for _, tri in kept for v in tri])
    grid = [grid_for(lo[a], hi[a]) for a in range(3)]
    if vertex_format == VERTS_Q16:
        stored = {v: [nearest_q(positions[v][a], *grid[a]) for a in range(3)] for _, tri in kept for v in tri}
        decoded = {v: [deq(q[a], *grid[a]) for a in range(3)] for v, q in stored.items()}
    else:
        stored = decoded = {v: positions[v] for _, tri in kept for v in tri}
    if layout == BINARY:
        ndata, cooked, depth, node_count = place_binary(tree, decoded, grid)
        first_use = cooked
    else:
        ndata, cooked, depth, node_count, first_use = place_wide4(tree, decoded, grid, depth_first)
    if tri_encoding == TRIS_LOCAL8:
        vorder, ctris = number_local8(cooked)
    else:
        # vertices by first use in the depth-first order of the leaves (spec section 4, DELTA16)
        vmap = {}
        for _, tri in first_use:
            for v in tri:
                vmap.setdefault(v, len(vmap))
        vorder = list(vmap)
        ctris = [[vmap[v] for v in tri] for _, tri in cooked]
    vdata = b"".join(struct.pack("<3H" if vertex_format == VERTS_Q16 else "<3f", *stored[v]) for v in vorder)
    bmin, bmax = box_of(list(decoded.values()))

    if tri_encoding is None:
        tri_encoding = TRIS_U16 if len(vorder) <= 65536 else TRIS_U32
    if tri_encoding == TRIS_LOCAL8:
        tdata = local8_bytes(ctris)
    elif tri_encoding == TRIS_U16:
        tdata = b"".join(struct.pack("<3H", *t) for t in ctris)
    elif tri_encoding == TRIS_U32:
        tdata = b"".join(struct.pack("<3I", *t) for t in ctris)
    else:
        tdata = b"".join(struct.pack("<Ihh", t[0], t[1] - t[0], t[2] - t[0]) for t in ctris)

    original = len(triangles) if keep_remap else len(cooked)
    sections = [
        Section(NODES, layout, ndata, codec),
        Section(TRIANGLES, tri_encoding, tdata, codec),
        Section(VERTICES, vertex_format, vdata, codec),
    ]
    if keep_remap and ([i for i, _ in cooked] != list(range(len(triangles))) or remap_encoding is not None):
        enc = remap_encoding
        if enc is None:  # u16, else u24, else u32
            enc = 0 if original <= 65536 else REMAP_U24 if original <= 1 << 24 else 1
        width = {0: 2, 1: 4, REMAP_U24: 3}[enc]
        sections.append(Section(REMAP, enc, b"".join(i.to_bytes(width, "little") for i, _ in cooked), codec))
    elif keep_remap:
        original = len(cooked)
    if materials is not None:
        ids = [materials[i] for i, _ in cooked]
        enc = material_encoding
        if enc is None:
            enc = 0 if max(ids) < 256 else 1 if max(ids) < 65536 else 2
        sections.append(Section(MATERIALS, enc, b"".join(struct.pack("<" + "BHI"[enc], m) for m in ids), codec))
    header = dict(version=1, header_size=HEADER_SIZE, compat=compat_flags,
                  incompat=INCOMPAT_W4_DEPTH_FIRST if depth_first else 0,
                  triangle_count=len(cooked), vertex_count=len(vorder), node_count=node_count, depth=depth,
                  max_leaf_size=max_leaf, original_triangle_count=original,
                  grid_origin=[g[0] for g in grid], grid_scale=[g[1] for g in grid], bounds_min=bmin, bounds_max=bmax,
                  reserved=bytes(12))
    return header, sections


# ---------------------------------------------------------------- serialization


class Section:
    """One section: its decoded bytes plus optional overrides of what the writer would put in its table entry.
    The stored bytes always go at the next multiple of 64: an overridden offset only changes the entry."""

    def __init__(self, type_, encoding, data, codec=RAW):
        self.type, self.encoding, self.data, self.codec = type_, encoding, data, codec
        self.stored = None  # stored bytes (default: data, or its zlib stream)
        self.offset = None  # table entry overrides (default: what the writer computes)
        self.size = None
        self.stored_size = None
        self.crc = None

    def stored_bytes(self):
        if self.stored is not None:
            return self.stored
        return zlib.compress(self.data, 9) if self.codec == ZLIB else self.data


def align(n):
    return (n + ALIGN - 1) // ALIGN * ALIGN


def serialize(header, sections, section_count=None, table_crc=None, header_crc=None, file_size=None):
    count = len(sections) if section_count is None else section_count
    out = bytearray(HEADER_SIZE + ENTRY_SIZE * len(sections))
    entries = []
    for s in sections:
        stored = s.stored_bytes()
        offset = align(len(out))
        out += bytes(offset - len(out)) + stored
        entries.append(struct.pack("<IIQQQII", s.type, s.codec, offset if s.offset is None else s.offset,
                                   len(stored) if s.stored_size is None else s.stored_size,
                                   len(s.data) if s.size is None else s.size,
                                   zlib.crc32(stored) if s.crc is None else s.crc, s.encoding))
    table = b"".join(entries)
    h = header
    raw = MAGIC + struct.pack("<IIIIII", h["version"], h["header_size"], h["compat"], h["incompat"], count,
                              zlib.crc32(table) if table_crc is None else table_crc)
    raw += struct.pack("<6I", h["triangle_count"], h["vertex_count"], h["node_count"], h["depth"],
                       h["max_leaf_size"], h["original_triangle_count"])
    for key in ("grid_origin", "grid_scale", "bounds_min", "bounds_max"):
        raw += struct.pack("<3f", *h[key])
    raw += struct.pack("<Q", len(out) if file_size is None else file_size) + h["reserved"]
    raw += struct.pack("<I", zlib.crc32(raw) if header_crc is None else header_crc)
    assert len(raw) == HEADER_SIZE
    out[:HEADER_SIZE + len(table)] = raw + table
    return bytes(out)


# ---------------------------------------------------------------- meshes

SINGLE = ([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.5)], [(0, 1, 2)])


def box_mesh(offset=0.0):
    xs, ys, zs = (-1.5 + offset, 2.25 + offset), (0.0, 3.0), (1.0, 5.0)
    v = [(xs[i & 1], ys[i >> 1 & 1], zs[i >> 2 & 1]) for i in range(8)]
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    t = []
    for a, b, c, d in faces:
        t += [(a, b, c), (a, c, d)]
    return v, t


BOX = box_mesh()
# the box and a copy 10 along x: with leaves of 1 its wide4 tree has two nodes with children on one level, so
# the leaves' breadth-first and depth-first orders differ
TWO_BOXES = (BOX[0] + box_mesh(10.0)[0], BOX[1] + [tuple(v + 8 for v in t) for t in BOX[1]])
BOX_FAR = box_mesh(70000.0)
QUAD = ([(0.0, 0.0, 2.5), (4.0, 0.0, 2.5), (4.0, 2.0, 2.5), (0.0, 2.0, 2.5)], [(0, 1, 2), (0, 2, 3)])
# The box with two degenerate triangles (dropped by the cooker) at original ids 3 and 9.
BOX_DEGENERATE = (BOX[0], BOX[1][:3] + [(0, 0, 1)] + BOX[1][3:8] + [(2, 5, 2)] + BOX[1][8:])

# The quad's two triangles at original ids 1 and 4 of 5, the rest degenerate: original ids are sparse
# (original_triangle_count 5 > 2 x triangle_count), which a reader may handle differently.
QUAD_SPARSE = (QUAD[0], [(0, 0, 1), QUAD[1][0], (1, 1, 1), (2, 3, 2), QUAD[1][1]])


def materials_for(mesh, base):
    return [base + 7 * i for i in range(len(mesh[1]))]


# ---------------------------------------------------------------- vectors

VECTORS = []  # (name, expected result, check that fires, description, builder returning bytes)


def vector(name, expected, check, description):
    def register(fn):
        VECTORS.append((name, expected, check, description, fn))
        return fn
    return register


def box(**kw):
    return cook(*BOX, max_leaf=2, **kw)


def find(sections, type_):
    return next(s for s in sections if s.type == type_)


def patched(sec, offset, fmt, value):
    data = bytearray(sec.data)
    struct.pack_into(fmt, data, offset, value)
    sec.data = bytes(data)


@vector("good-single-triangle", "OK", "-", "1 triangle, 3 f32 vertices, a single leaf as root (node_count 1, depth 1)")
def _():
    return serialize(*cook(*SINGLE))


@vector("good-box-raw", "OK", "-", "box, 12 triangles, leaves of at most 2: 15 nodes, depth 4, u16 indices, f32 vertices, raw")
def _():
    return serialize(*box())


@vector("good-box-zlib", "OK", "-", "good-box-raw with every section zlib-compressed")
def _():
    return serialize(*box(codec=ZLIB))


@vector("good-box-u32", "OK", "-", "good-box-raw with u32 vertex indices")
def _():
    return serialize(*box(tri_encoding=TRIS_U32))


@vector("good-box-delta16", "OK", "-", "good-box-raw with DELTA16 triangles (negative deltas included)")
def _():
    return serialize(*box(tri_encoding=TRIS_DELTA16))


@vector("good-box-q16", "OK", "-", "good-box-raw with 16-bit grid vertices (lossy: within half a grid step)")
def _():
    return serialize(*box(vertex_format=VERTS_Q16))


@vector("good-box-far-q16", "OK", "-", "the box moved 70 km along x, grid vertices, zlib")
def _():
    return serialize(*cook(*BOX_FAR, max_leaf=2, vertex_format=VERTS_Q16, codec=ZLIB))


@vector("good-quad-flat", "OK", "-", "2 triangles in the plane z = 2.5: grid_scale z is 0, all qmin/qmax z are 65535")
def _():
    return serialize(*cook(*QUAD, max_leaf=1))


@vector("good-remap-materials", "OK", "-",
        "box with 2 degenerate triangles (original ids 3 and 9) dropped: REMAP u16, MATERIALS u8 (id 1 + 7 x original id)")
def _():
    return serialize(*cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 1)))


@vector("good-remap-u32-materials-u32-zlib", "OK", "-",
        "as good-remap-materials with REMAP u32, MATERIALS u32 (id 70000 + 7 x original id), zlib, DELTA16")
def _():
    return serialize(*cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 70000),
                           remap_encoding=1, tri_encoding=TRIS_DELTA16, codec=ZLIB))


@vector("good-remap-sparse", "OK", "-",
        "the quad's 2 triangles at original ids 1 and 4 of 5 (ids 0, 2, 3 degenerate), REMAP u16, MATERIALS u8 (3 + 7 x id)")
def _():
    return serialize(*cook(*QUAD_SPARSE, max_leaf=1, materials=materials_for(QUAD_SPARSE, 3), remap_encoding=0))


@vector("good-remap-u24", "OK", "-", "as good-remap-materials with REMAP u24 (3 bytes per original id)")
def _():
    return serialize(*cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 1),
                           remap_encoding=REMAP_U24))


@vector("bad-remap-u24-range", "CORRUPT", "original id 16777215",
        "good-remap-u24 with the first id 0xFFFFFF, past original_triangle_count 14")
def _():
    h, s = cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 1), remap_encoding=REMAP_U24)
    r = find(s, REMAP)
    r.data = b"\xff\xff\xff" + r.data[3:]
    return serialize(h, s)


@vector("good-materials-u16-cooked-ids", "OK", "-",
        "box without REMAP (ids are cooked ids), MATERIALS u16 (id 1000 + 7 x original id, in cooked order)")
def _():
    return serialize(*box(keep_remap=False, materials=materials_for(BOX, 1000)))


@vector("good-ancillary", "OK", "-",
        "good-box-raw plus two unknown ancillary sections (type 0x80000007 raw; 0x80000009 with codec 9, encoding 42): skipped")
def _():
    h, s = box()
    a = Section(0x80000007, 0, b"future data", RAW)
    b = Section(0x80000009, 42, b"\x01\x02\x03", RAW)
    b.codec = 9
    return serialize(h, s[:2] + [a] + s[2:] + [b])


@vector("good-compat-flags", "OK", "-", "good-box-raw with compat_flags 0x80000005 (unknown compatible features)")
def _():
    return serialize(*box(compat_flags=0x80000005))


def good_box():
    return serialize(*box())


def entry_offset(data, i):
    """The offset in table entry i of a serialized file."""
    return struct.unpack_from("<Q", data, HEADER_SIZE + ENTRY_SIZE * i + 8)[0]


@vector("bad-empty", "CORRUPT", "empty", "0 bytes")
def _():
    return b""


@vector("bad-magic", "CORRUPT", "bad magic", "good-box-raw with magic byte 1 ('C') changed to 'c'")
def _():
    d = bytearray(good_box())
    d[1] = ord("c")
    return bytes(d)


@vector("bad-text-mode", "CORRUPT", "text-mode", "good-box-raw after a text-mode transfer turned CR LF into LF")
def _():
    return good_box().replace(b"\r\n", b"\n")


@vector("bad-version-0", "CORRUPT", "format version 0", "format_version 0 (header CRC valid)")
def _():
    h, s = box()
    h["version"] = 0
    return serialize(h, s)


@vector("bad-truncated-header", "CORRUPT", "truncated", "good-box-raw cut to 100 bytes")
def _():
    return good_box()[:100]


@vector("bad-header-crc", "CORRUPT", "header CRC", "good-box-raw with a wrong header_crc32")
def _():
    h, s = box()
    return serialize(h, s, header_crc=0x12345678)


@vector("bad-header-size", "CORRUPT", "header_size", "header_size 64")
def _():
    h, s = box()
    h["header_size"] = 64
    return serialize(h, s)


@vector("bad-reserved", "CORRUPT", "reserved byte", "reserved header byte 115 set to 1")
def _():
    h, s = box()
    h["reserved"] = bytes(3) + b"\x01" + bytes(8)
    return serialize(h, s)


@vector("bad-section-count", "CORRUPT", "section_count", "section_count 2")
def _():
    h, s = box()
    return serialize(h, s[:2], section_count=2)


@vector("bad-triangle-count", "CORRUPT", "triangle_count", "triangle_count 0")
def _():
    h, s = box()
    h["triangle_count"] = 0
    return serialize(h, s)


@vector("bad-vertex-count", "CORRUPT", "vertex_count", "vertex_count 37, more than 3 x triangle_count (36)")
def _():
    h, s = box()
    h["vertex_count"] = 37
    return serialize(h, s)


@vector("bad-node-count", "CORRUPT", "node_count", "node_count 0")
def _():
    h, s = box()
    h["node_count"] = 0
    return serialize(h, s)


@vector("bad-depth-limit", "CORRUPT", "depth 65", "depth 65, beyond the limit of 64")
def _():
    h, s = box()
    h["depth"] = 65
    return serialize(h, s)


@vector("bad-max-leaf-size", "CORRUPT", "max_leaf_size 17", "max_leaf_size 17")
def _():
    h, s = box()
    h["max_leaf_size"] = 17
    return serialize(h, s)


@vector("bad-original-count", "CORRUPT", "original_triangle_count 11 is below",
        "original_triangle_count 11 < triangle_count 12")
def _():
    h, s = box()
    h["original_triangle_count"] = 11
    return serialize(h, s)


@vector("bad-grid-nan", "CORRUPT", "grid on axis y", "grid_origin y is NaN")
def _():
    h, s = box()
    h["grid_origin"][1] = float("nan")
    return serialize(h, s)


@vector("bad-grid-overflow", "CORRUPT", "overflows", "grid_scale x 1e36: coordinate 65535 dequantizes to infinity")
def _():
    h, s = box()
    h["grid_scale"][0] = 1e36
    return serialize(h, s)


@vector("bad-bounds-inverted", "CORRUPT", "bounds on axis z", "bounds_min z > bounds_max z")
def _():
    h, s = box()
    h["bounds_min"][2], h["bounds_max"][2] = h["bounds_max"][2], h["bounds_min"][2]
    return serialize(h, s)


@vector("bad-truncated", "CORRUPT", "(truncated)", "good-box-raw without its last byte")
def _():
    return good_box()[:-1]


@vector("bad-trailing-byte", "CORRUPT", "(trailing bytes)", "good-box-raw plus one zero byte")
def _():
    return good_box() + b"\0"


@vector("bad-trailing-section-gap", "CORRUPT", "trailing bytes: the last section ends",
        "64 zero bytes after the last section, counted in file_size")
def _():
    h, s = box()
    n = len(serialize(h, s))
    d = bytearray(serialize(h, s, file_size=n + 64) + bytes(64))
    return bytes(d)


@vector("bad-table-crc", "CORRUPT", "section table CRC", "wrong table_crc32")
def _():
    h, s = box()
    return serialize(h, s, table_crc=1)


@vector("bad-table-past-end", "CORRUPT", "section table ends", "single triangle with section_count 16: the table would end at byte 768 of 420")
def _():
    h, s = cook(*SINGLE)
    return serialize(h, s, section_count=16)


@vector("bad-section-crc", "CORRUPT", "CRC mismatch", "one byte of the NODES section changed, CRC left alone")
def _():
    h, s = box()
    s[0].crc = zlib.crc32(s[0].data)
    patched(s[0], 12, "<I", struct.unpack_from("<I", s[0].data, 12)[0] ^ 0x100)
    return serialize(h, s)


@vector("bad-section-misaligned", "CORRUPT", "not a multiple of 64", "TRIANGLES section at offset 580 = 64 x 9 + 4")
def _():
    h, s = box()
    s[1].offset = entry_offset(good_box(), 1) + 4
    assert s[1].offset == 580
    return serialize(h, s)


@vector("bad-section-overlap", "CORRUPT", "overlaps", "TRIANGLES section at offset 384, inside NODES [320, 560)")
def _():
    h, s = box()
    s[1].offset = 384
    assert entry_offset(good_box(), 0) == 320  # NODES: bytes [320, 560)
    return serialize(h, s)


@vector("bad-section-over-table", "CORRUPT", "overlaps the section table", "NODES section at offset 256, inside the table [128, 288)")
def _():
    h, s = box()
    s[0].offset = 256
    return serialize(h, s)


@vector("bad-section-past-end", "CORRUPT", "run past the end", "VERTICES stored_size 2^64 - 1 (offset + size wraps)")
def _():
    h, s = box()
    s[2].stored_size = 2 ** 64 - 1
    return serialize(h, s)


@vector("bad-padding", "CORRUPT", "byte 575: padding before section 1", "byte 575, in the padding between NODES [320, 560) and TRIANGLES (576), is 1")
def _():
    d = bytearray(good_box())
    assert entry_offset(d, 1) == 576
    d[575] = 1
    return bytes(d)


@vector("bad-duplicate-section", "CORRUPT", "second VERTICES", "two VERTICES sections")
def _():
    h, s = box()
    return serialize(h, s + [Section(VERTICES, 0, s[2].data)])


@vector("bad-duplicate-ancillary", "CORRUPT", "second section of type 0x80000007",
        "two unknown ancillary sections of the same type 0x80000007")
def _():
    h, s = box()
    return serialize(h, s + [Section(0x80000007, 0, b"one"), Section(0x80000007, 0, b"two")])


@vector("bad-missing-nodes", "CORRUPT", "required section NODES", "the NODES section typed as an ancillary section")
def _():
    h, s = box()
    s[0].type = 0x80000001
    return serialize(h, s)


@vector("bad-section-size", "CORRUPT", "size 132, expected 144", "u32 TRIANGLES section of 132 bytes (11 triangles) for triangle_count 12")
def _():
    h, s = cook(*BOX, max_leaf=2, tri_encoding=TRIS_U32)
    s[1].data = s[1].data[:132]
    return serialize(h, s)


@vector("bad-raw-stored-size", "CORRUPT", "stored_size", "raw NODES section with stored_size 256 != size 240")
def _():
    h, s = box()
    s[0].stored = s[0].data + bytes(16)
    s[0].size = len(s[0].data)
    return serialize(h, s)


@vector("bad-zlib-short", "CORRUPT", "inflates to 66 bytes", "zlib TRIANGLES stream inflating to 66 bytes, size 72")
def _():
    h, s = box(codec=ZLIB)
    s[1].stored = zlib.compress(s[1].data[:-6], 9)
    return serialize(h, s)


@vector("bad-zlib-long", "CORRUPT", "more than its size", "zlib TRIANGLES stream inflating to 6 bytes more than its size")
def _():
    h, s = box(codec=ZLIB)
    s[1].stored = zlib.compress(s[1].data + s[1].data[:6], 9)
    return serialize(h, s)


@vector("bad-zlib-trailing", "CORRUPT", "ends at stored byte", "zlib NODES stream followed by 2 stored bytes")
def _():
    h, s = box(codec=ZLIB)
    s[0].stored = zlib.compress(s[0].data, 9) + b"\0\0"
    return serialize(h, s)


@vector("bad-zlib-cut", "CORRUPT", "cut short", "zlib VERTICES stream without its last 5 bytes")
def _():
    h, s = box(codec=ZLIB)
    s[2].stored = zlib.compress(s[2].data, 9)[:-5]
    return serialize(h, s)


@vector("bad-zlib-garbage", "CORRUPT", "bad zlib stream", "zlib NODES section holding bytes that are not a zlib stream")
def _():
    h, s = box(codec=ZLIB)
    s[0].stored = bytes(range(40, 80))
    return serialize(h, s)


def box_nodes():
    h, s = box()
    return h, s, s[0]


@vector("bad-root-size", "CORRUPT", "node 0: subtree size 9", "root subtree size 9 != node_count 11")
def _():
    h, s, n = box_nodes()
    w = struct.unpack_from("<I", n.data, 12)[0]
    patched(n, 12, "<I", (w & ~0x7FFFFF) | 9)
    return serialize(h, s)


@vector("bad-escape-self", "CORRUPT", "has subtree size 0", "node 1 (internal) with subtree size 0: its escape link would loop")
def _():
    h, s, n = box_nodes()
    w = struct.unpack_from("<I", n.data, 16 + 12)[0]
    patched(n, 16 + 12, "<I", w & ~0x7FFFFF)
    return serialize(h, s)


@vector("bad-escape-past-parent", "CORRUPT", "leaving no room", "node 1 with subtree size 14: no room is left for the root's second child")
def _():
    h, s, n = box_nodes()
    w = struct.unpack_from("<I", n.data, 16 + 12)[0]
    patched(n, 16 + 12, "<I", (w & ~0x7FFFFF) | 14)
    return serialize(h, s)


def second_child_of_root(n):
    w1 = struct.unpack_from("<I", n.data, 16 + 12)[0]
    return 1 + (1 if w1 & LEAF_BIT else w1 & 0x7FFFFF)


@vector("bad-second-child", "CORRUPT", "but its parent leaves it nodes", "root's second child (node 8) with subtree size 3 instead of 7: its escape link is not the root's")
def _():
    h, s, n = box_nodes()
    c = second_child_of_root(n)
    w = struct.unpack_from("<I", n.data, 16 * c + 12)[0]
    patched(n, 16 * c + 12, "<I", (w & ~0x7FFFFF) | 3)
    return serialize(h, s)


def leaf_nodes(n):
    return [i for i in range(len(n.data) // 16) if struct.unpack_from("<I", n.data, 16 * i + 12)[0] & LEAF_BIT]


@vector("bad-leaf-past-end", "CORRUPT", "run past triangle_count", "last leaf holds triangles [11, 14) (max_leaf_size raised to 4)")
def _():
    h, s, n = box_nodes()
    h["max_leaf_size"] = 4
    last = leaf_nodes(n)[-1]
    patched(n, 16 * last + 12, "<I", LEAF_BIT | 2 << 27 | 11)
    return serialize(h, s)


@vector("bad-leaf-gap", "CORRUPT", "previous leaf ended at 1", "second leaf starts at triangle 2 instead of 1")
def _():
    h, s, n = box_nodes()
    second = leaf_nodes(n)[1]
    patched(n, 16 * second + 12, "<I", LEAF_BIT | 1 << 27 | 2)
    return serialize(h, s)


@vector("bad-leaves-short", "CORRUPT", "leaves cover triangles [0, 12), triangle_count is 13",
        "a 13th triangle in TRIANGLES (triangle_count 13) that no leaf covers")
def _():
    return with_uncovered_triangle(*box(keep_remap=False))


def with_uncovered_triangle(h, s):
    """A file without REMAP plus a 13th triangle (triangle_count 13) that no leaf covers."""
    h["triangle_count"] = h["original_triangle_count"] = 13
    s[1].data += s[1].data[:6]
    return serialize(h, s)


@vector("bad-leaf-too-big", "CORRUPT", "more than max_leaf_size", "max_leaf_size 1 with leaves of 2")
def _():
    h, s = box()
    h["max_leaf_size"] = 1
    return serialize(h, s)


@vector("bad-depth-mismatch", "CORRUPT", "the tree's depth is 4", "header depth 5, tree depth 4")
def _():
    h, s = box()
    h["depth"] += 1
    return serialize(h, s)


@vector("bad-depth-exceeded", "CORRUPT", "deeper than the header", "header depth 3, tree depth 4")
def _():
    h, s = box()
    h["depth"] -= 1
    return serialize(h, s)


@vector("bad-qmin-gt-qmax", "CORRUPT", "node 2: qmin 100 > qmax 50 on axis 1", "node 2 with qmin y 100 > qmax y 50")
def _():
    h, s, n = box_nodes()
    patched(n, 32 + 2, "<H", 100)
    patched(n, 32 + 8, "<H", 50)
    return serialize(h, s)


@vector("bad-index-u16", "CORRUPT", "triangle 5 (cooked order): vertex indices", "u16 index of triangle 5 = vertex_count (8)")
def _():
    h, s = box()
    patched(s[1], 5 * 6 + 2, "<H", 8)
    return serialize(h, s)


@vector("bad-index-u32", "CORRUPT", "triangle 11 (cooked order): vertex indices", "u32 index of the last triangle = 2^32 - 1")
def _():
    h, s = box(tri_encoding=TRIS_U32)
    patched(s[1], 11 * 12 + 8, "<I", 0xFFFFFFFF)
    return serialize(h, s)


@vector("bad-delta16-negative", "CORRUPT", "DELTA16", "DELTA16 triangle 0: base 0, d1 -1 (index -1, no wrap-around)")
def _():
    h, s = box(tri_encoding=TRIS_DELTA16)
    patched(s[1], 0, "<I", 0)
    patched(s[1], 4, "<h", -1)
    return serialize(h, s)


@vector("bad-delta16-wrap", "CORRUPT", "DELTA16", "DELTA16 triangle 1: base 2^32 - 1, d1 = d2 = 1 (wraps to 0 in 32 bits)")
def _():
    h, s = box(tri_encoding=TRIS_DELTA16)
    d = bytearray(s[1].data)
    struct.pack_into("<Ihh", d, 8, 0xFFFFFFFF, 1, 1)
    s[1].data = bytes(d)
    return serialize(h, s)


@vector("bad-vertex-nan", "CORRUPT", "vertex 3: coordinate 2", "f32 vertex 3's z is NaN")
def _():
    h, s = box()
    patched(s[2], 3 * 12 + 8, "<f", float("nan"))
    return serialize(h, s)


@vector("bad-bounds-mismatch", "CORRUPT", "differ from the vertices' bounds", "bounds_max x 2.5, the vertices reach 2.25")
def _():
    h, s = box()
    h["bounds_max"][0] = 2.5
    return serialize(h, s)


@vector("bad-remap-duplicate", "CORRUPT", "both hold original id", "REMAP entry 5 equal to entry 4")
def _():
    h, s = cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 1))
    r = find(s, REMAP)
    patched(r, 10, "<H", struct.unpack_from("<H", r.data, 8)[0])
    return serialize(h, s)


@vector("bad-remap-range", "CORRUPT", "original_triangle_count is 14", "REMAP entry 0 = 14 = original_triangle_count")
def _():
    h, s = cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 1))
    patched(find(s, REMAP), 0, "<H", 14)
    return serialize(h, s)


def sparse_remap():
    h, s = cook(*QUAD_SPARSE, max_leaf=1, materials=materials_for(QUAD_SPARSE, 3), remap_encoding=0)
    return h, s, find(s, REMAP)


@vector("bad-remap-duplicate-sparse", "CORRUPT", "REMAP entries 0 and 1 both hold original id 4",
        "good-remap-sparse with both REMAP entries 4")
def _():
    h, s, r = sparse_remap()
    patched(r, 0, "<H", 4)
    patched(r, 2, "<H", 4)
    return serialize(h, s)


@vector("bad-remap-range-sparse", "CORRUPT", "REMAP entry 1: original id 5", "good-remap-sparse with REMAP entry 1 = 5")
def _():
    h, s, r = sparse_remap()
    patched(r, 2, "<H", 5)
    return serialize(h, s)


@vector("bad-remap-missing", "CORRUPT", "without a REMAP section", "original_triangle_count 14 != triangle_count 12 and no REMAP")
def _():
    h, s = cook(*BOX_DEGENERATE, max_leaf=2)
    return serialize(h, [x for x in s if x.type != REMAP])


@vector("unsupported-version-2", "UNSUPPORTED", "format version 2",
        "format_version 2 with a 256-byte header and a header CRC a v1 reader would call wrong: version comes first")
def _():
    d = bytearray(good_box())
    struct.pack_into("<II", d, 8, 2, 256)
    return bytes(d)


@vector("unsupported-incompat-flag", "UNSUPPORTED", "incompatible feature flags", "incompat_flags 0x1")
def _():
    h, s = box()
    h["incompat"] = 1
    return serialize(h, s)


@vector("unsupported-codec", "UNSUPPORTED", "codec 2", "NODES section with codec 2")
def _():
    h, s = box()
    s[0].codec = 2
    return serialize(h, s)


@vector("unsupported-encoding", "UNSUPPORTED", "encoding 3", "TRIANGLES section with encoding 3")
def _():
    h, s = box()
    s[1].encoding = 3
    return serialize(h, s)


@vector("unsupported-critical-section", "UNSUPPORTED", "critical section type 6", "an extra section of unknown type 6 (bit 31 clear)")
def _():
    h, s = box()
    return serialize(h, s + [Section(6, 0, b"new critical data")])


# ---------------------------------------------------------------- material ids and names (spec section 4)


def names_data(entries, count=None, offsets=None, tail=b""):
    """MATERIAL_NAMES encoding 0: u32 count, (u32 id, u32 offset) per name, the names NUL-terminated."""
    blob, offs = b"", []
    for _, name in entries:
        offs.append(len(blob))
        blob += name.encode("utf-8") + b"\0"
    offs = offsets if offsets is not None else offs
    table = b"".join(struct.pack("<II", i, o) for (i, _), o in zip(entries, offs))
    return struct.pack("<I", len(entries) if count is None else count) + table + blob + tail


NAMES = [(3, "Glass"), (7, "Oak"), (7, "Steel \u00fc")]  # sorted by (id, UTF-8 bytes)


def uniform_box(material=7, names=None, names_encoding=0, codec=RAW):
    h, s = box()
    s.append(Section(MATERIALS, MATS_UNIFORM, struct.pack("<I", material)))
    if names is not None:
        s.append(Section(MATERIAL_NAMES, names_encoding, names, codec))
    return h, s


@vector("good-materials-uniform", "OK", "-", "good-box-raw with MATERIALS encoding 3: one u32 id, 7, for every triangle")
def _():
    return serialize(*uniform_box())


@vector("good-material-names", "OK", "-",
        "good-materials-uniform plus a MATERIAL_NAMES section: 3 'Glass', 7 'Oak', 7 'Steel \u00fc' (UTF-8)")
def _():
    return serialize(*uniform_box(names=names_data(NAMES)))


@vector("good-material-names-zlib", "OK", "-", "good-material-names with the MATERIAL_NAMES section zlib-compressed")
def _():
    return serialize(*uniform_box(names=names_data(NAMES), codec=ZLIB))


@vector("good-material-names-future", "OK", "-",
        "good-materials-uniform plus a MATERIAL_NAMES section of unknown encoding 1: skipped (no names)")
def _():
    return serialize(*uniform_box(names=b"\xff" * 7, names_encoding=1))


@vector("bad-materials-uniform-size", "CORRUPT", "size 8, expected 4",
        "good-materials-uniform with an 8-byte uniform MATERIALS section")
def _():
    h, s = box()
    return serialize(h, s + [Section(MATERIALS, MATS_UNIFORM, struct.pack("<II", 7, 7))])


@vector("bad-names-order", "CORRUPT", "not after name 1",
        "good-material-names with the names of id 7 in decreasing order")
def _():
    return serialize(*uniform_box(names=names_data([NAMES[0], NAMES[2], NAMES[1]])))


@vector("bad-names-duplicate", "CORRUPT", "name 2 (id 7) is not after",
        "good-material-names with the same (id, name) twice")
def _():
    return serialize(*uniform_box(names=names_data(NAMES[:2] + [NAMES[1]])))


@vector("bad-names-offset", "CORRUPT", "name 1 starts at offset 7",
        "good-material-names with the second offset 7 instead of 6")
def _():
    return serialize(*uniform_box(names=names_data(NAMES, offsets=[0, 7, 10])))


@vector("bad-names-no-nul", "CORRUPT", "no terminating NUL", "good-material-names without the last name's NUL")
def _():
    return serialize(*uniform_box(names=names_data(NAMES)[:-1]))


@vector("bad-names-trailing", "CORRUPT", "1 bytes after the last name", "good-material-names with a byte after the last name")
def _():
    return serialize(*uniform_box(names=names_data(NAMES, tail=b"x")))


@vector("bad-names-count", "CORRUPT", "1000 names do not fit", "good-material-names with a count of 1000")
def _():
    return serialize(*uniform_box(names=names_data(NAMES, count=1000)))


@vector("bad-names-empty", "CORRUPT", "size 0; it must be 4 to", "good-materials-uniform with an empty MATERIAL_NAMES section")
def _():
    return serialize(*uniform_box(names=b""))


@vector("bad-names-too-big", "CORRUPT", "size 16777217; it must be 4 to",
        "good-material-names-zlib whose table entry claims 16 MiB + 1 bytes inflated")
def _():
    h, s = uniform_box(names=names_data(NAMES), codec=ZLIB)
    s[-1].size = (16 << 20) + 1
    return serialize(h, s)


@vector("bad-names-second", "CORRUPT", "second MATERIAL_NAMES section", "good-material-names with its names section twice")
def _():
    h, s = uniform_box(names=names_data(NAMES))
    return serialize(h, s + [Section(MATERIAL_NAMES, 0, names_data(NAMES))])


@vector("unsupported-materials-encoding-4", "UNSUPPORTED", "encoding 4", "good-materials-uniform with MATERIALS encoding 4")
def _():
    h, s = uniform_box()
    s[-1].encoding = 4
    return serialize(h, s)


# ---------------------------------------------------------------- wide4 vectors (NODES encoding 1, spec section 5.2)


def w4box(max_leaf=1, **kw):
    """The box in wide4 nodes. Leaves of 1: 5 nodes, depth 3, the slots below (u: used, i: internal):
    node 0 u 1111 i 1110, node 1 u 0011, node 2 u 0111, node 3 u 1111 i 1000, node 4 u 0111."""
    return cook(*BOX, max_leaf=max_leaf, layout=WIDE4, **kw)


def w4_node(sec, i, edit):
    """Applies edit(first_child, first_triangle, meta, planes) -> the same four to node i of a NODES section;
    planes[p][s] is plane p (qmin x, y, z, qmax x, y, z) of slot s."""
    data = bytearray(sec.data)
    q = list(struct.unpack_from("<24H", data, 64 * i))
    fc, ft, meta = struct.unpack_from("<IIQ", data, 64 * i + 48)
    planes = [q[4 * p:4 * p + 4] for p in range(6)]
    fc, ft, meta, planes = edit(fc, ft, meta, planes)
    struct.pack_into("<24HIIQ", data, 64 * i, *[v for plane in planes for v in plane], fc, ft, meta)
    sec.data = bytes(data)


def w4_edited(i, edit, **kw):
    h, s = w4box(**kw)
    w4_node(s[0], i, edit)
    return serialize(h, s)


def w4_header(max_leaf=1, **fields):
    """The wide4 box with header fields changed."""
    h, s = w4box(max_leaf)
    h.update(fields)
    return serialize(h, s)


@vector("good-w4-single-triangle", "OK", "-", "wide4: 1 triangle, a single-leaf root (node_count 1, depth 1, the leaf in slot 0)")
def _():
    return serialize(*cook(*SINGLE, layout=WIDE4))


@vector("good-w4-box-raw", "OK", "-", "wide4: box, leaves of at most 2: 3 nodes, depth 2 (root: 2 leaves, 2 internal slots), raw")
def _():
    return serialize(*w4box(2))


@vector("good-w4-box-zlib", "OK", "-", "good-w4-box-raw with every section zlib-compressed")
def _():
    return serialize(*w4box(2, codec=ZLIB))


@vector("good-w4-box-leaf1", "OK", "-", "wide4: box, leaves of 1: 5 nodes, depth 3, unused slots in nodes 1, 2 and 4")
def _():
    return serialize(*w4box())


@vector("good-w4-box-leaf8", "OK", "-", "wide4: box with max_leaf_size 8 (the wide4 limit): one node, two leaves of 6")
def _():
    return serialize(*w4box(8))


@vector("good-w4-box-q16", "OK", "-", "good-w4-box-raw with 16-bit grid vertices")
def _():
    return serialize(*w4box(2, vertex_format=VERTS_Q16))


@vector("good-w4-box-far-q16", "OK", "-", "wide4: the box moved 70 km along x, leaves of 2, grid vertices, zlib")
def _():
    return serialize(*cook(*BOX_FAR, max_leaf=2, vertex_format=VERTS_Q16, codec=ZLIB, layout=WIDE4))


@vector("good-w4-quad-flat", "OK", "-", "wide4: the flat quad, leaves of 1: one node of 2 leaf slots, grid_scale z 0")
def _():
    return serialize(*cook(*QUAD, max_leaf=1, layout=WIDE4))


@vector("good-w4-remap-materials", "OK", "-", "wide4: box degenerate, leaves of 2: REMAP u16, MATERIALS u8 (1 + 7 x original id)")
def _():
    return serialize(*cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 1), layout=WIDE4))


@vector("good-w4-remap-u32-materials-u32-zlib", "OK", "-",
        "as good-w4-remap-materials with REMAP u32, MATERIALS u32 (70000 + 7 x original id), zlib, DELTA16")
def _():
    return serialize(*cook(*BOX_DEGENERATE, max_leaf=2, materials=materials_for(BOX_DEGENERATE, 70000),
                           remap_encoding=1, tri_encoding=TRIS_DELTA16, codec=ZLIB, layout=WIDE4))


@vector("good-w4-materials-u16-cooked-ids", "OK", "-", "good-w4-box-raw without REMAP, MATERIALS u16 (1000 + 7 x original id)")
def _():
    return serialize(*w4box(2, keep_remap=False, materials=materials_for(BOX, 1000)))


@vector("bad-w4-no-slot", "CORRUPT", "node 1: no slot in use", "good-w4-box-leaf1 with node 1's meta 0")
def _():
    return w4_edited(1, lambda fc, ft, meta, q: (fc, ft, 0, q))


@vector("bad-w4-internal-unused", "CORRUPT", "node 0: slots 0x8 are internal but not in use",
        "good-w4-box-leaf1 with the root's slot 3 internal but its in-use bit clear")
def _():
    return w4_edited(0, lambda fc, ft, meta, q: (fc, ft, meta & ~(1 << 19), q))


def set_plane(q, p, s, v):
    q[p][s] = v
    return q


@vector("bad-w4-unused-box", "CORRUPT", "node 1: unused slot 3 has a nonzero box", "good-w4-box-leaf1 with node 1's unused slot 3 qmax z 1")
def _():
    return w4_edited(1, lambda fc, ft, meta, q: (fc, ft, meta, set_plane(q, 5, 3, 1)))


@vector("bad-w4-unused-count", "CORRUPT", "node 1: slot 2 is unused but has a triangle count field of 1",
        "good-w4-box-leaf1 with node 1's unused slot 2 count field 1")
def _():
    return w4_edited(1, lambda fc, ft, meta, q: (fc, ft, meta | 1 << 8, q))


@vector("bad-w4-internal-count", "CORRUPT", "node 0: slot 1 is internal but has a triangle count field of 1",
        "good-w4-box-leaf1 with the root's internal slot 1 count field 1")
def _():
    return w4_edited(0, lambda fc, ft, meta, q: (fc, ft, meta | 1 << 4, q))


@vector("bad-w4-leaf-too-big", "CORRUPT", "node 0: slot 1 is a leaf of 2 triangles, more than max_leaf_size 1",
        "good-w4-box-raw with max_leaf_size 1")
def _():
    return w4_header(2, max_leaf_size=1)


@vector("bad-w4-max-leaf-size", "CORRUPT", "max_leaf_size 9 is more than a wide4 leaf holds (8)",
        "good-w4-box-raw with max_leaf_size 9 (valid for binary nodes, above the wide4 limit)")
def _():
    return w4_header(2, max_leaf_size=9)


@vector("bad-w4-triangle-count", "CORRUPT", "triangle_count 268435457 is outside 1..268435456",
        "good-w4-box-leaf1 with triangle_count 2^28 + 1")
def _():
    return w4_header(triangle_count=2 ** 28 + 1)


@vector("bad-w4-qmin-gt-qmax", "CORRUPT", "node 2: slot 1: qmin 100 > qmax 50 on axis 1",
        "good-w4-box-leaf1 with node 2's slot 1 qmin y 100 > qmax y 50")
def _():
    return w4_edited(2, lambda fc, ft, meta, q: (fc, ft, meta, set_plane(set_plane(q, 1, 1, 100), 4, 1, 50)))


@vector("bad-w4-order-index", "CORRUPT", "node 3: order index 24 for octant 5 is not below 24",
        "good-w4-box-leaf1 with node 3's order for octant 5 = 24")
def _():
    return w4_edited(3, lambda fc, ft, meta, q: (fc, ft, meta & ~(31 << 49) | 24 << 49, q))


@vector("bad-w4-first-child", "CORRUPT", "node 0: first_child 2, but the nodes before it leave the next child at 1",
        "good-w4-box-leaf1 with the root's first_child 2 (its 3 children [2, 5) would still fit)")
def _():
    return w4_edited(0, lambda fc, ft, meta, q: (2, ft, meta, q))


@vector("bad-w4-first-child-self", "CORRUPT", "node 3: first_child 3, but the nodes before it leave the next child at 4",
        "good-w4-box-leaf1 with node 3's first_child 3: its internal slot would be itself (a loop)")
def _():
    return w4_edited(3, lambda fc, ft, meta, q: (3, ft, meta, q))


@vector("bad-w4-children-past-end", "CORRUPT", "node 3: children [4, 5) run past node_count 4",
        "good-w4-box-leaf1 without its last node (node_count 4): node 3's internal child is missing")
def _():
    h, s = w4box()
    h["node_count"] = 4
    s[0].data = s[0].data[:4 * 64]
    return serialize(h, s)


@vector("bad-w4-unallocated-node", "CORRUPT", "node 5: no node before it has it as a child",
        "good-w4-box-leaf1 plus a sixth node (a copy of node 4) that no node allocates")
def _():
    h, s = w4box()
    h["node_count"] = 6
    s[0].data += s[0].data[4 * 64:]
    return serialize(h, s)


@vector("bad-w4-first-triangle", "CORRUPT", "node 2: first_triangle 4, but the leaves before it end at triangle 3",
        "good-w4-box-leaf1 with node 2's first_triangle 4 instead of 3")
def _():
    return w4_edited(2, lambda fc, ft, meta, q: (fc, 4, meta, q))


@vector("bad-w4-leaves-past-end", "CORRUPT", "node 4: slot 2's triangles [11, 13) run past triangle_count 12",
        "good-w4-box-leaf1 with node 4's last leaf holding 2 triangles (max_leaf_size raised to 2)")
def _():
    h, s = w4box()
    h["max_leaf_size"] = 2
    w4_node(s[0], 4, lambda fc, ft, meta, q: (fc, ft, meta | 1 << 8, q))
    return serialize(h, s)


@vector("bad-w4-leaves-short", "CORRUPT", "leaves cover triangles [0, 12), triangle_count is 13",
        "good-w4-box-leaf1 without REMAP and a 13th triangle that no leaf covers")
def _():
    return with_uncovered_triangle(*w4box(keep_remap=False))


@vector("bad-w4-depth-mismatch", "CORRUPT", "the tree's depth is 3, the header says 4", "good-w4-box-leaf1 with header depth 4")
def _():
    return w4_header(depth=4)


@vector("bad-w4-depth-exceeded", "CORRUPT", "node 4: at depth 3, deeper than the header's depth 2",
        "good-w4-box-leaf1 with header depth 2")
def _():
    return w4_header(depth=2)


@vector("good-box-local8", "OK", "-",
        "good-box-raw with LOCAL8 triangles (TRIANGLES encoding 4): 2 blocks, the second holding 4 triangles")
def _():
    return serialize(*box(tri_encoding=TRIS_LOCAL8))


@vector("bad-local8-index", "CORRUPT", "LOCAL8 base 7 plus offset",
        "good-box-local8 with block 0's base 7: base plus its largest offset is past vertex_count 8")
def _():
    h, s = box(tri_encoding=TRIS_LOCAL8)
    patched(s[1], 0, "<I", 7)
    return serialize(h, s)


@vector("bad-local8-padding", "CORRUPT", "offset 1 of slot 4, past triangle_count 12, must be 0",
        "good-box-local8 with an offset of 1 in block 1's slot 4 (triangle 12, past the last)")
def _():
    h, s = box(tri_encoding=TRIS_LOCAL8)
    patched(s[1], 28 + 4 + 3 * 4, "<B", 1)
    return serialize(h, s)


@vector("bad-local8-size", "CORRUPT", "expected 56 (2 elements of 28 bytes)",
        "good-box-local8 with a third, empty block (84 bytes for 12 triangles)")
def _():
    h, s = box(tri_encoding=TRIS_LOCAL8)
    s[1].data += bytes(28)
    return serialize(h, s)


@vector("good-two-boxes", "OK", "-", "two boxes 10 apart along x, 24 triangles, leaves of 1, binary nodes")
def _():
    return serialize(*cook(*TWO_BOXES, max_leaf=1))


def w4_two_boxes(**kw):
    return cook(*TWO_BOXES, max_leaf=1, layout=WIDE4, **kw)


@vector("good-w4-two-boxes", "OK", "-",
        "good-two-boxes in wide4 nodes, leaves breadth first (as cooked before the depth-first flag)")
def _():
    return serialize(*w4_two_boxes())


@vector("good-w4-two-boxes-local8", "OK", "-",
        "good-two-boxes in wide4 nodes with incompat flag 0x2 (leaves depth first) and LOCAL8 triangles, as the "
        "cooker writes it")
def _():
    h, s = w4_two_boxes(depth_first=True, tri_encoding=TRIS_LOCAL8)
    assert find(s, NODES).data != find(w4_two_boxes()[1], NODES).data, "the two orders must differ here"
    return serialize(h, s)


@vector("good-w4-local8-q16-zlib", "OK", "-",
        "wide4 box with 2 degenerate triangles dropped, depth-first leaves, LOCAL8, grid vertices, REMAP u16, "
        "MATERIALS u8 (1 + 7 x original id), every section zlib")
def _():
    return serialize(*cook(*BOX_DEGENERATE, max_leaf=2, layout=WIDE4, depth_first=True, tri_encoding=TRIS_LOCAL8,
                           vertex_format=VERTS_Q16, materials=materials_for(BOX_DEGENERATE, 1), codec=ZLIB))


@vector("bad-w4-depth-first-unflagged", "CORRUPT", "but the leaves before it end at triangle",
        "good-w4-two-boxes-local8 without incompat flag 0x2: its leaves do not tile breadth first")
def _():
    h, s = w4_two_boxes(depth_first=True, tri_encoding=TRIS_LOCAL8)
    h["incompat"] = 0
    return serialize(h, s)


@vector("bad-w4-flag-breadth-first", "CORRUPT", "in depth-first order end at triangle",
        "good-w4-two-boxes with incompat flag 0x2: its leaves do not tile depth first")
def _():
    h, s = w4_two_boxes()
    h["incompat"] = INCOMPAT_W4_DEPTH_FIRST
    return serialize(h, s)


@vector("bad-depth-first-binary", "CORRUPT", "depth-first flag is set on a binary-layout file",
        "good-box-raw with incompat flag 0x2, which only wide4 nodes may have")
def _():
    h, s = box()
    h["incompat"] = INCOMPAT_W4_DEPTH_FIRST
    return serialize(h, s)


@vector("unsupported-w4-nodes-encoding-2", "UNSUPPORTED", "encoding 2", "good-w4-box-leaf1 with NODES encoding 2 (a future node layout)")
def _():
    h, s = w4box()
    s[0].encoding = 2
    return serialize(h, s)


def main(argv):
    if argv[1:] == ["--table"]:
        print("| file | expected | check (message contains) | content |")
        print("|---|---|---|---|")
        for name, expected, check, description, _ in VECTORS:
            print(f"| `{name}.cbvh` | {expected} | {check} | {description} |")
        return 0
    if argv[1:] == ["--am"]:
        print("# fileformat: the normative spec and the test vectors (list regenerated with: "
              "python3 fileformat/make_vectors.py --am).")
        print("EXTRA_DIST += fileformat/cbvh-format.md fileformat/README.md fileformat/make_vectors.py")
        print("EXTRA_DIST +=" + "".join(f" \\\n\tfileformat/{name}.cbvh" for name in sorted(v[0] for v in VECTORS)))
        return 0
    out = argv[1] if len(argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    os.makedirs(out, exist_ok=True)
    for name, _, _, _, fn in VECTORS:
        with open(os.path.join(out, name + ".cbvh"), "wb") as f:
            f.write(fn())
    print(f"wrote {len(VECTORS)} vectors to {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
