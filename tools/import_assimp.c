/* import_assimp.c: loads a mesh file with assimp and merges its node hierarchy into one triangle list. */
#include <errno.h>
#include <fnmatch.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <zlib.h>

#include "import_assimp.h"

/* Node hierarchies deeper than this are refused rather than risking the C stack. */
#define IMPORT_MAX_NODE_DEPTH 4096

typedef struct import_state {
    const struct aiScene *scene;
    imported_mesh *out;
    int counting;          /* first pass: count only; second pass: fill */
    uint64_t vertex_total; /* vertices counted or written so far */
    uint64_t triangle_total;
    unsigned char *instanced; /* per scene mesh: a node refers to it */
    const char *select;       /* only nodes matching this pattern, with their subtrees (NULL: all) */
    char *message;
    size_t message_size;
} import_state;

/* Row-major 4x4 affine transform acting on column vectors (assimp's convention). */
typedef struct dmat4 {
    double m[4][4];
} dmat4;

static dmat4 dmat4_from_ai(const struct aiMatrix4x4 *a)
{
    dmat4 r = {{{a->a1, a->a2, a->a3, a->a4},
                {a->b1, a->b2, a->b3, a->b4},
                {a->c1, a->c2, a->c3, a->c4},
                {a->d1, a->d2, a->d3, a->d4}}};
    return r;
}

static dmat4 dmat4_mul(const dmat4 *a, const dmat4 *b)
{
    dmat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            r.m[i][j] = a->m[i][0] * b->m[0][j] + a->m[i][1] * b->m[1][j] + a->m[i][2] * b->m[2][j] +
                        a->m[i][3] * b->m[3][j];
    return r;
}

/* Appends (or, in the counting pass, counts) one mesh reference under `xf`. */
static int import_mesh_instance(import_state *s, const struct aiMesh *mesh, const dmat4 *xf)
{
    imported_mesh *out = s->out;
    uint64_t base = s->vertex_total;
    if ((mesh->mNumVertices && !mesh->mVertices) || (mesh->mNumFaces && !mesh->mFaces)) {
        snprintf(s->message, s->message_size,
                 "mesh '%s' lists %u vertices and %u faces but lacks their arrays", mesh->mName.data,
                 mesh->mNumVertices, mesh->mNumFaces);
        return 1;
    }
    if (!s->counting) {
        float *p = out->positions + 3 * base;
        for (unsigned v = 0; v < mesh->mNumVertices; v++) {
            double x = mesh->mVertices[v].x, y = mesh->mVertices[v].y, z = mesh->mVertices[v].z;
            /* A NaN or infinite coordinate would spread to every axis through the transform (inf * 0): kept
             * as the file has it, so the cook's refusal names the axis and the kind the file holds. */
            const int finite = isfinite(x) && isfinite(y) && isfinite(z);
            for (int r = 0; r < 3; r++)
                p[3 * v + r] =
                    finite ? (float)(xf->m[r][0] * x + xf->m[r][1] * y + xf->m[r][2] * z + xf->m[r][3])
                           : (float)(r == 0   ? x
                                     : r == 1 ? y
                                              : z);
        }
    }
    s->vertex_total += mesh->mNumVertices;
    for (unsigned f = 0; f < mesh->mNumFaces; f++) {
        const struct aiFace *face = &mesh->mFaces[f];
        if (face->mNumIndices == 1) {
            out->dropped_points += s->counting;
            continue;
        }
        if (face->mNumIndices == 2) {
            out->dropped_lines += s->counting;
            continue;
        }
        if (face->mNumIndices != 3) {
            snprintf(s->message, s->message_size, "mesh '%s': face %u has %u indices after triangulation",
                     mesh->mName.data, f, face->mNumIndices);
            return 1;
        }
        if (s->counting) {
            for (int k = 0; k < 3; k++) {
                if (face->mIndices[k] >= mesh->mNumVertices) {
                    snprintf(s->message, s->message_size, "mesh '%s': face %u uses vertex %u of %u",
                             mesh->mName.data, f, face->mIndices[k], mesh->mNumVertices);
                    return 1;
                }
            }
        } else {
            uint32_t *ix = out->indices + 3 * s->triangle_total;
            for (int k = 0; k < 3; k++)
                ix[k] = (uint32_t)(base + face->mIndices[k]);
            out->material_ids[s->triangle_total] = mesh->mMaterialIndex;
        }
        s->triangle_total++;
    }
    out->mesh_instances += s->counting;
    return 0;
}

static int import_node(import_state *s, const struct aiNode *node, const dmat4 *parent, int depth,
                       int selected)
{
    if (depth > IMPORT_MAX_NODE_DEPTH) {
        snprintf(s->message, s->message_size, "node hierarchy deeper than %d levels", IMPORT_MAX_NODE_DEPTH);
        return 1;
    }
    dmat4 local = dmat4_from_ai(&node->mTransformation);
    dmat4 xf = dmat4_mul(parent, &local);
    selected = selected || !s->select || fnmatch(s->select, node->mName.data, 0) == 0;
    if (node->mNumMeshes && !node->mMeshes) {
        snprintf(s->message, s->message_size, "node '%s' lists %u meshes but holds none", node->mName.data,
                 node->mNumMeshes);
        return 1;
    }
    for (unsigned i = 0; selected && i < node->mNumMeshes; i++) {
        unsigned m = node->mMeshes[i];
        if (m >= s->scene->mNumMeshes || !s->scene->mMeshes || !s->scene->mMeshes[m]) {
            snprintf(s->message, s->message_size, "node '%s' refers to mesh %u of %u, which is missing",
                     node->mName.data, m, s->scene->mNumMeshes);
            return 1;
        }
        if (import_mesh_instance(s, s->scene->mMeshes[m], &xf))
            return 1;
        s->instanced[m] = 1;
    }
    /* Some importers (RAW) count more children than they fill: an empty slot holds nothing to import. */
    for (unsigned c = 0; node->mChildren && c < node->mNumChildren; c++)
        if (node->mChildren[c] && import_node(s, node->mChildren[c], &xf, depth + 1, selected))
            return 1;
    return 0;
}

static const dmat4 identity = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};

/* The hierarchy depth first, then each mesh that no node refers to, once and untransformed (an importer
 * that loses a node must not lose its triangles). */
static int import_pass(import_state *s)
{
    memset(s->instanced, 0, s->scene->mNumMeshes + 1u);
    if (import_node(s, s->scene->mRootNode, &identity, 0, 0))
        return 1;
    for (unsigned m = 0; !s->select && m < s->scene->mNumMeshes; m++)
        if (!s->instanced[m] && s->scene->mMeshes && s->scene->mMeshes[m] &&
            import_mesh_instance(s, s->scene->mMeshes[m], &identity))
            return 1;
    return 0;
}

/* After the counting pass: allocates the arrays and fills them in a second pass. */
static int import_counted(import_state *s)
{
    imported_mesh *out = s->out;
    if (s->triangle_total == 0 && s->select) {
        snprintf(s->message, s->message_size, "no triangles in the nodes that --select '%s' matches",
                 s->select);
        return 1;
    }
    if (s->triangle_total == 0) {
        snprintf(s->message, s->message_size, "no triangles (%llu points and %llu lines dropped)",
                 (unsigned long long)out->dropped_points, (unsigned long long)out->dropped_lines);
        return 1;
    }
    /* Indices are 32-bit in cbvh_mesh. */
    if (s->vertex_total > UINT32_MAX || s->triangle_total > UINT32_MAX) {
        snprintf(s->message, s->message_size,
                 "too large: %llu vertices, %llu triangles (at most 2^32-1 each)",
                 (unsigned long long)s->vertex_total, (unsigned long long)s->triangle_total);
        return 1;
    }
    out->vertex_count = (size_t)s->vertex_total;
    out->triangle_count = (size_t)s->triangle_total;
    out->positions = malloc(out->vertex_count * 3 * sizeof(float));
    out->indices = malloc(out->triangle_count * 3 * sizeof(uint32_t));
    out->material_ids = malloc(out->triangle_count * sizeof(uint32_t));
    if (!out->positions || !out->indices || !out->material_ids) {
        snprintf(s->message, s->message_size, "out of memory for %zu vertices and %zu triangles",
                 out->vertex_count, out->triangle_count);
        return 2;
    }
    s->counting = 0;
    s->vertex_total = 0;
    s->triangle_total = 0;
    out->material_count = s->scene->mNumMaterials;
    if (out->material_count > 0) {
        out->material_names = calloc(out->material_count, sizeof *out->material_names);
        if (!out->material_names) {
            snprintf(s->message, s->message_size, "out of memory for %u material names", out->material_count);
            return 2;
        }
    }
    for (uint32_t k = 0; k < out->material_count; k++) {
        struct aiString name;
        if (s->scene->mMaterials[k] &&
            aiGetMaterialString(s->scene->mMaterials[k], AI_MATKEY_NAME, &name) == aiReturn_SUCCESS &&
            name.length > 0 && memchr(name.data, 0, name.length) == NULL)
            out->material_names[k] = strdup(name.data); /* NULL (no name) when out of memory */
    }
    return import_pass(s);
}

static int import_scene(const struct aiScene *scene, const char *select, imported_mesh *out, char *message,
                        size_t message_size)
{
    import_state s = {scene, out, 1, 0, 0, NULL, select, message, message_size};
    if (!scene->mRootNode) {
        snprintf(message, message_size, "the scene has no node hierarchy");
        return 1;
    }
    s.instanced = malloc(scene->mNumMeshes + 1u);
    if (!s.instanced) {
        snprintf(message, message_size, "out of memory for %u meshes", scene->mNumMeshes);
        return 2;
    }
    int rc = import_pass(&s);
    if (rc == 0)
        rc = import_counted(&s);
    free(s.instanced);
    return rc;
}

/* assimp's file system, recording every file an import opens (for --depfile): a stdio file (on disk, or over
 * the inflated bytes of a .gz input) behind each aiFile, the import_options behind the aiFileIO. Reads are
 * bounded: a seek past the end fails, and a reader that keeps asking for bytes at the end of the file
 * (assimp's PLY header parser does, on a file cut inside its header) is reported through
 * o->on_runaway_read, since assimp cannot be made to stop from here. */
typedef struct io_file {
    FILE *file;
    size_t size;
    unsigned long reads_at_end; /* reads that returned nothing */
    int is_input;               /* the asset itself (not a side file): its reads are the import's progress */
    int percent;                /* the last progress reported */
    import_options *o;
    char path[];
} io_file;

/* Reads that return nothing before the file counts as read in a loop: loaders probe the end a few times. */
#define IO_MAX_READS_AT_END 65536ul

static io_file *io_of(struct aiFile *f)
{
    return (io_file *)(void *)f->UserData;
}

static size_t io_read(struct aiFile *f, char *buffer, size_t size, size_t count)
{
    io_file *io = io_of(f);
    size_t n = size && count ? fread(buffer, size, count, io->file) : 0;
    if (n == 0 && size && count && ++io->reads_at_end > IO_MAX_READS_AT_END && io->o->on_runaway_read)
        io->o->on_runaway_read(io->o->hook_user, io->path);
    if (io->is_input && io->size && io->o->on_read_progress) {
        long at = ftell(io->file);
        int percent = at < 0 ? io->percent : (int)(100.0 * (double)at / (double)io->size);
        if (percent != io->percent) {
            io->percent = percent;
            io->o->on_read_progress(io->o->hook_user, percent);
        }
    }
    return n;
}

static size_t io_write(struct aiFile *f, const char *buffer, size_t size, size_t count)
{
    (void)f;
    (void)buffer;
    (void)size;
    (void)count;
    return 0; /* an import only reads */
}

static size_t io_tell(struct aiFile *f)
{
    long at = ftell(io_of(f)->file);
    return at < 0 ? 0 : (size_t)at;
}

static size_t io_size(struct aiFile *f)
{
    return io_of(f)->size;
}

static enum aiReturn io_seek(struct aiFile *f, size_t offset, enum aiOrigin origin)
{
    io_file *io = io_of(f);
    size_t base = origin == aiOrigin_SET ? 0 : origin == aiOrigin_CUR ? io_tell(f) : io->size;
    /* assimp passes a backward seek from the current position as a wrapped size_t */
    size_t target = base + offset;
    if (target > io->size || target > LONG_MAX)
        return aiReturn_FAILURE;
    return fseek(io->file, (long)target, SEEK_SET) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
}

static void io_flush(struct aiFile *f)
{
    (void)f;
}

static void path_list_add(path_list *l, const char *path)
{
    for (size_t k = 0; k < l->count; k++)
        if (!strcmp(l->paths[k], path))
            return;
    char **grown = realloc(l->paths, (l->count + 1) * sizeof *grown);
    if (!grown)
        return;
    l->paths = grown;
    if ((l->paths[l->count] = strdup(path)) != NULL)
        l->count++;
}

static void path_list_free(path_list *l)
{
    for (size_t k = 0; k < l->count; k++)
        free(l->paths[k]);
    free(l->paths);
    l->paths = NULL;
    l->count = 0;
}

/* The bytes of an inflated .gz input, served under its name without ".gz". */
typedef struct memory_file {
    const char *name;     /* the name assimp asks for */
    const char *recorded; /* the name the depfile lists (the .gz file) */
    char *data;
    size_t size;
} memory_file;

/* What the aiFileIO's user data points to. */
typedef struct io_system {
    import_options *o;
    const memory_file *memory; /* NULL when the input is read from disk */
    const char *input;         /* the name the asset is read under */
} io_system;

static struct aiFile *io_open(struct aiFileIO *fio, const char *path, const char *mode)
{
    io_system *sys = (io_system *)(void *)fio->UserData;
    import_options *o = sys->o;
    const memory_file *mem = sys->memory;
    const int in_memory = mem && !strcmp(path, mem->name);
    if (strchr(mode, 'w') || strchr(mode, 'a') || strchr(mode, '+'))
        return NULL;
    /* fmemopen refuses an empty buffer: an empty input is an empty file on disk no more than in memory */
    FILE *file = in_memory ? (mem->size ? fmemopen(mem->data, mem->size, "rb") : NULL) : fopen(path, "rb");
    if (!file) {
        /* assimp looks for a side file as named, as "./" + name, and when that fails under names it pastes
         * together from the folder and the path (they hold "//"): the first name is the one to report */
        if (!in_memory && errno == ENOENT && !strstr(path, "//"))
            path_list_add(&o->missing, strncmp(path, "./", 2) ? path : path + 2);
        return NULL;
    }
    size_t size = mem && in_memory ? mem->size : 0;
    if (!in_memory) {
        if (fseek(file, 0, SEEK_END) != 0 || ftell(file) < 0 || fseek(file, 0, SEEK_SET) != 0) {
            fclose(file); /* not a seekable file (a folder, a FIFO): nothing assimp can read */
            return NULL;
        }
        fseek(file, 0, SEEK_END);
        size = (size_t)ftell(file);
        fseek(file, 0, SEEK_SET);
    }
    const char *recorded = in_memory ? mem->recorded : path;
    struct aiFile *f = calloc(1, sizeof *f);
    io_file *io = malloc(sizeof *io + strlen(recorded) + 1);
    if (!f || !io) {
        free(f);
        free(io);
        fclose(file);
        return NULL;
    }
    io->file = file;
    io->size = size;
    io->reads_at_end = 0;
    io->is_input = sys->input && !strcmp(path, sys->input);
    io->percent = -1;
    io->o = o;
    strcpy(io->path, recorded);
    path_list_add(&o->opened, recorded);
    f->ReadProc = io_read;
    f->WriteProc = io_write;
    f->TellProc = io_tell;
    f->FileSizeProc = io_size;
    f->SeekProc = io_seek;
    f->FlushProc = io_flush;
    f->UserData = (aiUserData)(void *)io;
    return f;
}

static void io_close(struct aiFileIO *fio, struct aiFile *f)
{
    (void)fio;
    if (!f)
        return;
    fclose(io_of(f)->file);
    free(io_of(f));
    free(f);
}

void import_options_free(import_options *o)
{
    path_list_free(&o->opened);
    path_list_free(&o->missing);
}

/* Inflates a gzip file whole (assimp has no stream interface in its C API). */
static int read_gzip(const char *path, char **out_data, size_t *out_size, char *message, size_t message_size)
{
    gzFile gz = gzopen(path, "rb");
    if (!gz) {
        snprintf(message, message_size, "cannot open: %s", strerror(errno ? errno : ENOMEM));
        return 2;
    }
    size_t size = 0, cap = 1 << 20;
    char *data = malloc(cap);
    for (;;) {
        if (!data) {
            gzclose(gz);
            snprintf(message, message_size, "out of memory inflating");
            return 2;
        }
        int n = gzread(gz, data + size, (unsigned)(cap - size));
        if (n < 0) {
            int zerr = 0;
            const char *what = gzerror(gz, &zerr);
            snprintf(message, message_size, "bad gzip data: %s", what);
            free(data);
            gzclose(gz);
            return zerr == Z_ERRNO ? 2 : 1;
        }
        if (n == 0)
            break;
        size += (size_t)n;
        if (size == cap) {
            if (cap >= UINT_MAX / 2) {
                snprintf(message, message_size, "inflates to more than 2 GiB, too large for assimp");
                free(data);
                gzclose(gz);
                return 1;
            }
            cap *= 2;
            char *grown = realloc(data, cap);
            if (!grown)
                free(data);
            data = grown;
        }
    }
    gzclose(gz);
    *out_data = data;
    *out_size = size;
    return 0;
}

/* cbvh's own checks of the scene assimp built, before its post-processing steps run on it: those trust the
 * importers, and on a truncated file an importer leaves faces with no indices or declares polygons it never
 * filled in (an ai_assert in TriangulateProcess aborts then). Returns 0 or 1 with a message. */
static int check_faces(const struct aiScene *scene, char *message, size_t message_size)
{
    for (unsigned m = 0; scene->mMeshes && m < scene->mNumMeshes; m++) {
        const struct aiMesh *mesh = scene->mMeshes[m];
        if (!mesh)
            continue;
        if ((mesh->mNumFaces && !mesh->mFaces) || (mesh->mNumVertices && !mesh->mVertices)) {
            snprintf(message, message_size, "mesh %u lists %u vertices and %u faces but lacks them", m,
                     mesh->mNumVertices, mesh->mNumFaces);
            return 1;
        }
        unsigned types = 0;
        for (unsigned f = 0; f < mesh->mNumFaces; f++) {
            const struct aiFace *face = &mesh->mFaces[f];
            if (face->mNumIndices == 0 || !face->mIndices) {
                snprintf(message, message_size, "mesh %u: face %u has no vertex indices (a truncated file?)",
                         m, f);
                return 1;
            }
            for (unsigned k = 0; k < face->mNumIndices; k++) {
                const unsigned v = face->mIndices[k];
                if (v >= mesh->mNumVertices) {
                    snprintf(message, message_size, "mesh %u: face %u uses vertex %u of %u", m, f, v,
                             mesh->mNumVertices);
                    return 1;
                }
                /* here, before assimp joins identical vertices (which merges a NaN one into another) */
                const float xyz[3] = {mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z};
                for (int a = 0; a < 3; a++)
                    if (!isfinite(xyz[a])) {
                        snprintf(
                            message, message_size,
                            "mesh %u: vertex %u (as assimp numbers them from 0; for OBJ one per face corner, "
                            "here face %u, corner %u): %c coordinate is %s",
                            m, v, f, k, "xyz"[a], isnan(xyz[a]) ? "NaN" : "infinite");
                        return 1;
                    }
            }
            types |= face->mNumIndices == 1   ? aiPrimitiveType_POINT
                     : face->mNumIndices == 2 ? aiPrimitiveType_LINE
                     : face->mNumIndices == 3 ? aiPrimitiveType_TRIANGLE
                                              : aiPrimitiveType_POLYGON;
        }
        if ((types & ~mesh->mPrimitiveTypes & 15u) ||
            ((mesh->mPrimitiveTypes & aiPrimitiveType_POLYGON) && !(types & aiPrimitiveType_POLYGON) &&
             mesh->mNumFaces)) {
            snprintf(
                message, message_size,
                "mesh %u: its faces are not of the kinds it declares (0x%x, faces 0x%x; a truncated file?)",
                m, mesh->mPrimitiveTypes, types);
            return 1;
        }
    }
    return 0;
}

/* Drops the empty slots some importers (RAW) leave among a node's children, which assimp's validation
 * refuses; the scene is ours until released, and aiNode frees only the children it counts. */
static void drop_empty_children(struct aiNode *node, int depth)
{
    if (!node || !node->mChildren || depth > IMPORT_MAX_NODE_DEPTH)
        return;
    unsigned kept = 0;
    for (unsigned c = 0; c < node->mNumChildren; c++)
        if (node->mChildren[c])
            node->mChildren[kept++] = node->mChildren[c];
    node->mNumChildren = kept;
    for (unsigned c = 0; c < kept; c++)
        drop_empty_children(node->mChildren[c], depth + 1);
}

/* Reads `name` through `sys`: assimp's parse and validation (aiProcess_ValidateDataStructure, run inside the
 * read, whose failure path is clean), cbvh's checks, then assimp's post-processing steps, then the merge. */
static int import_through(const char *name, io_system *sys, imported_mesh *out, char *message,
                          size_t message_size)
{
    struct aiFileIO io = {io_open, io_close, (aiUserData)(void *)sys};
    sys->input = name;
    const struct aiScene *scene = aiImportFileEx(name, aiProcess_ValidateDataStructure, &io);
    if (!scene && strstr(aiGetErrorString(), "node of the scene-graph is nullptr")) {
        /* the one defect validation refuses that cbvh repairs: read again unvalidated, then repair */
        scene = aiImportFileEx(name, 0, &io);
        if (scene)
            drop_empty_children(scene->mRootNode, 0);
    }
    if (!scene) {
        /* a point cloud fails validation before cbvh can count what it drops */
        const char *error = aiGetErrorString();
        snprintf(message, message_size, "%s: %s",
                 strstr(error, "contains no faces") ? "no triangles (a point cloud?)"
                                                    : "assimp cannot read it",
                 error);
        return 1;
    }
    if (check_faces(scene, message, message_size)) {
        aiReleaseImport(scene);
        return 1;
    }
    /* On failure assimp releases the scene itself (and assimp 5.2 then reads the freed scene: one more
     * reason the tool imports in a child process). */
    scene = aiApplyPostProcessing(scene, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                             aiProcess_SortByPType);
    if (!scene) {
        snprintf(message, message_size, "assimp's post-processing failed: %s", aiGetErrorString());
        return 1;
    }
    int rc = import_scene(scene, sys->o->select, out, message, message_size);
    aiReleaseImport(scene);
    if (rc)
        imported_mesh_free(out);
    return rc;
}

int import_assimp_memory(const void *data, size_t size, const char *name, import_options *o,
                         imported_mesh *out, char *message, size_t message_size)
{
    memset(out, 0, sizeof *out);
    import_options none;
    memset(&none, 0, sizeof none);
    memory_file mem = {name, name, (char *)(uintptr_t)data, size};
    io_system sys = {o ? o : &none, &mem, NULL};
    int rc = import_through(name, &sys, out, message, message_size);
    import_options_free(&none);
    return rc;
}

int import_assimp(const char *path, import_options *o, imported_mesh *out, char *message, size_t message_size)
{
    memset(out, 0, sizeof *out);
    import_options none;
    memset(&none, 0, sizeof none);
    io_system sys = {o ? o : &none, NULL, NULL};
    /* assimp reports "file not found" and "unknown format" alike; tell I/O errors apart first. */
    FILE *probe = fopen(path, "rb");
    if (!probe) {
        snprintf(message, message_size, "cannot open: %s", strerror(errno));
        return 2;
    }
    fclose(probe);

    int rc;
    size_t len = strlen(path);
    if (len > 3 && !strcmp(path + len - 3, ".gz")) {
        /* Read under the name without ".gz": its extension picks the format, its folder the side files. */
        memory_file mem = {NULL, path, NULL, 0};
        char *name = strdup(path);
        rc = name ? read_gzip(path, &mem.data, &mem.size, message, message_size) : 2;
        if (!name)
            snprintf(message, message_size, "out of memory");
        if (rc == 0) {
            name[len - 3] = '\0';
            mem.name = name;
            sys.memory = &mem;
            rc = import_through(name, &sys, out, message, message_size);
            free(mem.data);
        }
        free(name);
    } else {
        rc = import_through(path, &sys, out, message, message_size);
    }
    import_options_free(&none);
    return rc;
}

void imported_mesh_free(imported_mesh *m)
{
    free(m->positions);
    free(m->indices);
    free(m->material_ids);
    for (uint32_t k = 0; m->material_names && k < m->material_count; k++)
        free(m->material_names[k]);
    free(m->material_names);
    m->material_names = NULL;
    m->positions = NULL;
    m->indices = NULL;
    m->material_ids = NULL;
}
